// ngi.Frame, ngi.read_frame / write_frame, ngi.Pipeline (the surround-aware pipeline around a generator).
#include <cstring>
#include <optional>
#include <set>
#include <type_traits>

#include "common.hpp"
#include "model_ref.hpp"
#include "ngi/display.hpp"
#include "ngi/image_desc.hpp"
#include "ngi/image_io.hpp"
#include "ngi/pipeline.hpp"

namespace ngi_py {

namespace {

constexpr ngi::Feature kFeatures[] = {ngi::Feature::Albedo, ngi::Feature::Normal, ngi::Feature::Depth,
                                      ngi::Feature::Direct, ngi::Feature::Emission, ngi::Feature::Env};

bool optional_feature(ngi::Feature f) { return f == ngi::Feature::Emission || f == ngi::Feature::Env; }

// One feature of every face as [6, C, N, N] (a copy), or None when the frame does not have it.
py::object feature_array(const ngi::Frame& frame, ngi::Feature f) {
    const ngi::Image& front = frame.get(f, ngi::Face::Front);
    if (front.data.empty()) return py::none();
    const int c = front.channels, n = front.width;
    FloatArray out(std::vector<py::ssize_t>{ngi::kFaceCount, c, n, n});
    float* dst = out.mutable_data();
    for (int face = 0; face < ngi::kFaceCount; ++face) {
        const ngi::Image& img = frame.get(f, ngi::Face(face));
        std::memcpy(dst + std::size_t(face) * img.data.size(), img.data.data(), img.data.size() * sizeof(float));
    }
    return out;
}

// [faces, C, N, N] of a dict entry, checked: faces and N as given (0 = take from the array), C as the feature's.
FloatArray dict_feature(const py::dict& d, ngi::Feature f, int& faces, int& n) {
    const std::string key = ngi::feature_name(f);
    const std::string what = "frame['" + key + "']";
    FloatArray a = float_array(d[key.c_str()], what.c_str());
    const int c = ngi::feature_channels(f);
    const bool squeeze_ok = c == 1 && a.ndim() == 3;  // depth may be [faces, N, N]
    if (a.ndim() != 4 && !squeeze_ok)
        throw py::value_error(what + ": expected [faces, " + std::to_string(c) + ", N, N] (faces = 6, or 1 for the "
                              "front face only)");
    const int fa = int(a.shape(0)), ch = a.ndim() == 4 ? int(a.shape(1)) : 1;
    const int h = int(a.shape(a.ndim() - 2)), w = int(a.shape(a.ndim() - 1));
    if (ch != c || h != w || (fa != 1 && fa != ngi::kFaceCount))
        throw py::value_error(what + ": expected [faces, " + std::to_string(c) + ", N, N] with faces 6 or 1, got [" +
                              std::to_string(fa) + ", " + std::to_string(ch) + ", " + std::to_string(h) + ", " +
                              std::to_string(w) + "]");
    if (faces == 0) faces = fa;
    if (n == 0) n = h;
    if (fa != faces || h != n)
        throw py::value_error(what + ": " + std::to_string(fa) + " faces of N = " + std::to_string(h) +
                              ", the other features have " + std::to_string(faces) + " of N = " + std::to_string(n));
    return a;
}

// A Frame from a dict of [6, C, N, N] arrays (see Frame.from_dict).
ngi::Frame frame_from_dict(const py::dict& d) {
    ngi::Frame fr;
    int faces = 0, n = 0;
    for (ngi::Feature f : kFeatures) {
        if (!d.contains(ngi::feature_name(f))) {
            if (optional_feature(f)) continue;
            throw py::value_error(std::string("frame: the dict has no '") + ngi::feature_name(f) + "' entry");
        }
        FloatArray a = dict_feature(d, f, faces, n);
        if (faces != ngi::kFaceCount) throw py::value_error("Frame.from_dict: a Frame holds all six faces");
        const int c = ngi::feature_channels(f);
        for (int face = 0; face < ngi::kFaceCount; ++face) {
            ngi::Image img(n, n, c);
            std::memcpy(img.data.data(), a.data() + std::size_t(face) * img.data.size(), img.data.size() * sizeof(float));
            fr.get(f, ngi::Face(face)) = std::move(img);
        }
    }
    fr.n = n;
    if (d.contains("look")) fr.look = vec3(d["look"], "frame['look']");
    if (d.contains("up")) fr.up = vec3(d["up"], "frame['up']");
    if (d.contains("reference") && !d["reference"].is_none()) {
        fr.reference = to_image(d["reference"], "frame['reference']");
        if (fr.reference->channels != 3 || fr.reference->width != n || fr.reference->height != n)
            throw py::value_error("frame['reference']: expected [3, N, N] with N = " + std::to_string(n));
    }
    return fr;
}

// A dict of [faces, C, N, N] arrays packed straight into the frame-plane layout [faces][16][N][N].
std::vector<float> planes_from_dict(const py::dict& d, ngi::FrameDesc& desc, int& n) {
    int faces = 0;
    n = 0;
    std::vector<std::pair<ngi::Feature, FloatArray>> present;
    for (ngi::Feature f : kFeatures) {
        if (!d.contains(ngi::feature_name(f))) {
            if (optional_feature(f)) continue;
            throw py::value_error(std::string("frame: the dict has no '") + ngi::feature_name(f) + "' entry");
        }
        present.emplace_back(f, dict_feature(d, f, faces, n));
    }
    const std::size_t plane = std::size_t(n) * std::size_t(n);
    std::vector<float> planes(ngi::frame_planes_bytes(n, faces) / sizeof(float), 0.0f);
    for (const auto& [f, a] : present) {
        const int c = ngi::feature_channels(f), first = ngi::frame_plane(f);
        for (int face = 0; face < faces; ++face)
            std::memcpy(planes.data() + (std::size_t(face) * ngi::kFramePlanes + first) * plane,
                        a.data() + std::size_t(face) * c * plane, std::size_t(c) * plane * sizeof(float));
        if (f == ngi::Feature::Emission) desc.has_emission = true;
        if (f == ngi::Feature::Env) desc.has_env = true;
    }
    desc.faces = faces;
    if (d.contains("look")) desc.look = vec3(d["look"], "frame['look']");
    if (d.contains("up")) desc.up = vec3(d["up"], "frame['up']");
    return planes;
}

// An engine's render target as an image descriptor over a NumPy array (no copy): [H, W] or [H, W, C], float32,
// float16 or uint8, any positive strides (views, padded pitches, channel slices). `spec` is the array or a dict
// {"array": a, "srgb": bool, "scale": float, "bias": float, "bottom_up": bool}. `keep` holds the arrays alive.
// d[key] as T, or a TypeError naming `what`, the key, the type wanted and the type given (pybind11's own cast error
// names none of them: "Unable to cast Python instance to C++ type").
template <class T>
T dict_value(const py::dict& d, const char* key, const std::string& what, const char* wanted) {
    const py::object v = d[key];
    if (std::is_same_v<T, bool> && !py::isinstance<py::bool_>(v))  // 1 / "yes" would otherwise pass or fail obscurely
        throw py::type_error(what + ": '" + key + "' must be " + wanted + ", got " +
                             py::str(py::type::of(v).attr("__name__")).cast<std::string>());
    try {
        return v.cast<T>();
    } catch (const py::cast_error&) {
        throw py::type_error(what + ": '" + key + "' must be " + wanted + ", got " +
                             py::str(py::type::of(v).attr("__name__")).cast<std::string>());
    }
}

ngi::ImageDesc image_desc_from(const py::handle& spec, const std::string& what, std::vector<py::array>& keep) {
    py::object obj = py::reinterpret_borrow<py::object>(spec);
    bool srgb = false, bottom_up = false, reversed_z = false;
    float scale = 1.0f, bias = 0.0f, near_m = 0.0f, far_m = 0.0f;
    std::string format, normal = "xyz", depth = "linear";
    std::optional<py::array> to_world;
    static const std::set<std::string> kKeys = {"array", "srgb", "scale", "bias", "bottom_up", "format", "normal",
                                                "normal_to_world", "depth", "near", "far", "reversed_z"};
    if (py::isinstance<py::dict>(obj)) {
        py::dict d = obj.cast<py::dict>();
        for (auto item : d) {
            const std::string key = py::str(item.first);
            if (!kKeys.count(key))
                throw py::value_error(what + ": unknown key '" + key + "' (array, srgb, scale, bias, bottom_up, format, "
                                      "normal, normal_to_world, depth, near, far, reversed_z)");
        }
        if (!d.contains("array")) throw py::value_error(what + ": the dict has no 'array'");
        if (d.contains("srgb")) srgb = dict_value<bool>(d, "srgb", what, "True or False");
        if (d.contains("bottom_up")) bottom_up = dict_value<bool>(d, "bottom_up", what, "True or False");
        if (d.contains("scale")) scale = dict_value<float>(d, "scale", what, "a number");
        if (d.contains("bias")) bias = dict_value<float>(d, "bias", what, "a number");
        if (d.contains("format")) format = dict_value<std::string>(d, "format", what, "a format name");
        if (d.contains("normal")) normal = dict_value<std::string>(d, "normal", what, "'xyz' or 'octahedral'");
        if (d.contains("depth")) depth = dict_value<std::string>(d, "depth", what, "'linear' or 'perspective'");
        if (d.contains("near")) near_m = dict_value<float>(d, "near", what, "a number");
        if (d.contains("far")) far_m = dict_value<float>(d, "far", what, "a number");
        if (d.contains("reversed_z")) reversed_z = dict_value<bool>(d, "reversed_z", what, "True or False");
        if (d.contains("normal_to_world")) {
            to_world = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(d["normal_to_world"]);
            if (!*to_world || to_world->ndim() != 2 || to_world->shape(0) != 3 || to_world->shape(1) != 3)
                throw py::value_error(what + ": 'normal_to_world' must be a 3 x 3 array");
        }
        obj = d["array"];
    }
    if (!py::isinstance<py::array>(obj)) throw py::type_error(what + ": expected a NumPy array");
    py::array a = obj.cast<py::array>();
    if (a.ndim() != 2 && a.ndim() != 3) throw py::value_error(what + ": expected [H, W] or [H, W, C]");
    const py::dtype dt = a.dtype();
    ngi::ImageDesc d;
    if (!format.empty()) {
        d.format = ngi::pixel_format_from_name(format);  // InputError (a ValueError) for an unknown name
        const std::size_t bytes = ngi::pixel_format_bytes(d.format);
        if (std::size_t(dt.itemsize()) != bytes || (dt.kind() != 'u' && dt.kind() != 'i' && dt.kind() != 'f'))
            throw py::type_error(what + ": format " + format + " stores " + std::to_string(bytes) +
                                 "-byte values, the array's dtype is " + dt.attr("name").cast<std::string>());
    } else if (dt.is(py::dtype::of<float>())) d.format = ngi::PixelFormat::F32;
    else if (dt.kind() == 'f' && dt.itemsize() == 2) d.format = ngi::PixelFormat::F16;
    else if (dt.is(py::dtype::of<std::uint8_t>())) d.format = srgb ? ngi::PixelFormat::U8Srgb : ngi::PixelFormat::U8Unorm;
    else if (dt.is(py::dtype::of<std::uint16_t>())) d.format = ngi::PixelFormat::U16Unorm;
    else if (dt.is(py::dtype::of<std::int16_t>())) d.format = ngi::PixelFormat::S16Snorm;
    else throw py::type_error(what + ": dtype " + dt.attr("name").cast<std::string>() +
                              " is not float32, float16, uint8, uint16 or int16 (uint32 words of a packed format: give "
                              "'format')");
    if (srgb && d.format != ngi::PixelFormat::U8Srgb) throw py::value_error(what + ": srgb needs a uint8 array");
    for (int i = 0; i < a.ndim(); ++i)
        if (a.strides(i) <= 0)
            throw py::value_error(what + ": stride " + std::to_string(a.strides(i)) + " of axis " + std::to_string(i) +
                                  " is not positive (flipped rows: pass the unflipped array with bottom_up=True)");
    const int packed = ngi::pixel_format_packed_channels(d.format);
    if (packed && a.ndim() != 2)
        throw py::value_error(what + ": a packed format's array is [H, W] (one word per pixel)");
    d.height = int(a.shape(0));
    d.width = int(a.shape(1));
    d.channels = packed ? packed : a.ndim() == 3 ? int(a.shape(2)) : 1;
    d.row_stride = std::size_t(a.strides(0));
    d.pixel_stride = std::size_t(a.strides(1));
    d.channel_stride = packed ? 0 : a.ndim() == 3 ? std::size_t(a.strides(2)) : std::size_t(dt.itemsize());
    d.host = a.data();
    d.host_bytes = d.span_bytes();
    d.bottom_up = bottom_up;
    d.scale = scale;
    d.bias = bias;
    if (normal == "octahedral") d.normal_encoding = ngi::NormalEncoding::Octahedral;
    else if (normal != "xyz") throw py::value_error(what + ": 'normal' must be 'xyz' or 'octahedral', got '" + normal + "'");
    if (depth == "perspective") d.depth_encoding = ngi::DepthEncoding::Perspective;
    else if (depth != "linear") throw py::value_error(what + ": 'depth' must be 'linear' or 'perspective', got '" + depth + "'");
    d.near_m = near_m;
    d.far_m = far_m;
    d.reversed_z = reversed_z;
    if (to_world) {
        auto m = to_world->unchecked<float, 2>();
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) d.normal_to_world[c][r] = m(r, c);  // row-major in, glm column-major
    }
    keep.push_back(a);
    return d;
}

ngi::ToneMapOptions tonemap_options(float exposure_ev, const std::string& curve, bool srgb) {
    ngi::ToneMapOptions t;
    t.exposure_ev = exposure_ev;
    t.curve = ngi::tone_curve_from_name(curve);
    t.srgb = srgb;
    return t;
}

struct Wanted {
    bool lightmap = false, final_image = false, display = false;
};
Wanted wanted_outputs(const std::vector<std::string>& names) {
    Wanted w;
    for (const auto& s : names) {
        if (s == "lightmap") w.lightmap = true;
        else if (s == "final") w.final_image = true;
        else if (s == "display") w.display = true;
        else throw py::value_error("Pipeline.run: unknown output '" + s + "' (lightmap, final, display)");
    }
    if (!w.lightmap && !w.final_image && !w.display) throw py::value_error("Pipeline.run: no output asked for");
    return w;
}

// The images asked for, as run() returns them: 'lightmap', 'final', 'display'.
py::dict outputs_dict(const Wanted& w, ngi::FrameImages&& r) {
    py::dict out;
    if (w.lightmap) out["lightmap"] = from_image(std::move(r.lightmap));
    if (w.final_image) out["final"] = from_image(std::move(r.final_image));
    if (w.display) out["display"] = from_image(std::move(r.display));
    return out;
}

py::dict stats_dict(const ngi::PreprocessStats& s) {
    py::dict d, nonfinite;
    for (ngi::Feature f : kFeatures) nonfinite[ngi::feature_name(f)] = s.nonfinite[int(f)];
    d["nonfinite"] = nonfinite;
    d["sky_normals"] = s.sky_normals;
    d["far_depths"] = s.far_depths;
    return d;
}

// The config the network input follows: the model's, else the default surround (or single-view) layout, as
// `ngi merge` does without --model.
ngi::ModelConfig merge_config(const PyModel* model, bool single_view, const PyModel* ssgi) {
    if (ssgi) {
        // The input of a network that corrects this SSGI rung (output_mode "ssgi_residual"): what training needs
        // before any such network exists.
        if (model || single_view)
            throw py::value_error("network_input: ssgi excludes model and single_view (it makes the 13-channel input "
                                  "of a network that corrects that SSGI rung)");
        ssgi->device->get("network_input: ssgi");
        const ngi::ModelConfig& s = ssgi->model.config();
        if (s.has_network)  // an SSGI rung is a model with no network: its `ssgi` section is the gather's
            throw py::value_error("network_input: ssgi must be an SSGI rung (a model with no network, family ssgi), "
                                  "got family " + s.family);
        ngi::ModelConfig c;
        c.family = "pix2pix_unet";
        c.output_mode = "ssgi_residual";
        c.ssgi = s.ssgi;
        c.input_layout = ngi::ssgi_residual_input_channels();
        c.input_nc = int(c.input_layout.size());
        return c;
    }
    if (model) {
        if (single_view) throw py::value_error("network_input: single_view and model exclude each other");
        model->device->get("network_input: model");
        return model->model.config();
    }
    ngi::ModelConfig c;
    c.input_nc = single_view ? 10 : 12;
    c.input_layout = single_view ? ngi::single_view_input_channels() : ngi::surround_input_channels();
    return c;
}

struct PyPipeline {
    DeviceRef device;
    ngi::SurroundPipeline pipeline;
};

struct PyDisplayView {
    DeviceRef device;
    ngi::DisplayView view;
};

// A Frame argument: an ngi.Frame or a frame folder path.
std::shared_ptr<ngi::Frame> frame_arg(const py::object& frame, const char* what) {
    if (py::isinstance<ngi::Frame>(frame)) return frame.cast<std::shared_ptr<ngi::Frame>>();
    const std::string path = path_string(frame, what);
    py::gil_scoped_release release;
    return std::make_shared<ngi::Frame>(ngi::read_frame(path));
}

}  // namespace

void register_pipeline(py::module_& m) {
    py::class_<ngi::Frame, std::shared_ptr<ngi::Frame>>(m, "Frame", R"doc(
One frame of the camera cluster: every feature of the six N x N faces, the front camera's look and up, and
optionally the path-traced reference lighting of the front view (docs/CONVENTIONS.md). Faces in the order
front, back, left, right, up, down; features albedo (3), normal (3, world space), depth (1, metres), direct (3),
emission (3, optional), env (3, optional); planar, row 0 = top, linear values.)doc")
        .def_static("from_dict", &frame_from_dict, py::arg("planes"), R"doc(
A Frame from a dict: 'albedo', 'normal', 'depth', 'direct' (and optionally 'emission', 'env') as [6, C, N, N]
float arrays (depth may be [6, N, N]), 'look' and 'up' as three numbers, 'reference' as [3, N, N] or absent.)doc")
        .def("to_dict", [](const ngi::Frame& fr) {
            py::dict d;
            for (ngi::Feature f : kFeatures) {
                py::object a = feature_array(fr, f);
                if (!a.is_none()) d[ngi::feature_name(f)] = a;
            }
            d["look"] = tuple3(fr.look);
            d["up"] = tuple3(fr.up);
            if (fr.reference) d["reference"] = from_image(ngi::Image(*fr.reference));
            return d;
        }, "The frame as a dict of arrays (copies), the form Frame.from_dict and Pipeline.run take.")
        .def_readonly("n", &ngi::Frame::n, "Face size N in pixels.")
        .def_property_readonly("look", [](const ngi::Frame& fr) { return tuple3(fr.look); })
        .def_property_readonly("up", [](const ngi::Frame& fr) { return tuple3(fr.up); })
        .def_property_readonly("reference", [](const ngi::Frame& fr) -> py::object {
            if (!fr.reference) return py::none();
            return from_image(ngi::Image(*fr.reference));
        }, "The front view's reference lighting [3, N, N] (linear, irradiance / pi), or None.")
        .def("feature", [](const ngi::Frame& fr, const std::string& name) {
            for (ngi::Feature f : kFeatures)
                if (name == ngi::feature_name(f)) return feature_array(fr, f);
            throw py::value_error("Frame.feature: unknown feature '" + name +
                                  "' (albedo, normal, depth, direct, emission, env)");
        }, py::arg("name"), "One feature of all six faces as [6, C, N, N], or None if the frame does not have it.")
        .def("__repr__", [](const ngi::Frame& fr) {
            return "<ngi.Frame N = " + std::to_string(fr.n) + (fr.reference ? ", with reference" : "") + ">";
        });

    m.def("read_frame", [](const py::object& path) {
        const std::string p = path_string(path, "read_frame: path");
        py::gil_scoped_release release;
        return std::make_shared<ngi::Frame>(ngi::read_frame(p));
    }, py::arg("path"), "Read a frame folder (<face>_<feature>.exr/.png, camera.json, optional reference.exr); NaN/Inf "
                        "values are sanitized as docs/CONVENTIONS.md says.");
    m.def("write_frame", [](const py::object& path, const ngi::Frame& frame) {
        const std::string p = path_string(path, "write_frame: path");
        py::gil_scoped_release release;
        ngi::write_frame(p, frame);
    }, py::arg("path"), py::arg("frame"), "Write a frame folder (all files or none; see ngi/image_io.hpp).");
    m.def("surround_input_channels", &ngi::surround_input_channels,
          "Channel names of the surround-aware network input, in tensor order (12).");
    m.def("single_view_input_channels", &ngi::single_view_input_channels,
          "Channel names of the single-view network input, in tensor order (10).");
    m.def("ssgi_residual_input_channels", &ngi::ssgi_residual_input_channels,
          "Channel names of the input of a network that corrects SSGI (output_mode ssgi_residual), in order (13).");
    m.def("outside_light_share", [](const ngi::Frame& frame) { return ngi::outside_light_share(frame); },
          py::arg("frame"), R"doc(
The share of the frame's lumination (direct + emission + env, sanitized like the network input's; Rec. 709
luminance summed over each face) on the five faces other than the front: in [0, 1], 0 for a frame without light.
The per-frame switch of a plan (ngi.plan) runs the single-view model when it is below the plan's threshold.)doc");
    m.def("indirect_share", [](const ngi::Frame& frame, const py::object& lightmap) {
        const ngi::Image img = to_image(lightmap, "indirect_share: lightmap");
        py::gil_scoped_release release;  // a host loop over N x N x 3 values: other threads may run meanwhile
        return ngi::indirect_share(frame, img);
    }, py::arg("frame"), py::arg("lightmap"), R"doc(
The share of the front view's final image that `lightmap` ([3, N, N], linear) adds beyond the frame's direct light:
sum of Y(albedo * max(lightmap - direct, 0)) / sum of Y(final), final = albedo * lightmap + emission + env (the
terms the frame has), Y = Rec. 709 luminance, light terms and albedo sanitized as compose does (NaN, negative -> 0,
+Inf -> FLT_MAX; albedo clamped to [0, 1]), sums in double. In [0, 1]; 0 when nothing is lit. The signal of
`ngi lightmap --guard` (docs/CONVENTIONS.md section 17). InputError when the lightmap is not [3, N, N] or the frame
lacks the front albedo or direct light.)doc");

    py::class_<PyPipeline, std::shared_ptr<PyPipeline>>(m, "Pipeline", R"doc(
The surround-aware pipeline for face size N: preprocessing, MergeToGlobalView, coordinate map, the generator,
front-view extraction, decoding, compose and tone map (docs/CONVENTIONS.md).
Pipeline(device, n, mode="thesis" | "equirect", transfer="reinhard" | "clamp").)doc")
        .def(py::init([](const DeviceRef& device, int n, const std::string& mode, const std::string& transfer) {
                 const ngi::Device& dev = device->get("Pipeline");
                 const auto gm = ngi::global_view_mode_from_name(mode);
                 const auto lt = ngi::lumination_transfer_from_name(transfer);
                 py::gil_scoped_release release;
                 return std::make_shared<PyPipeline>(PyPipeline{device, ngi::SurroundPipeline(dev, n, gm, lt)});
             }),
             py::arg("device"), py::arg("n"), py::arg("mode") = "thesis", py::arg("transfer") = "reinhard")
        .def_property_readonly("n", [](const PyPipeline& p) { return p.pipeline.n(); })
        .def("run", [](PyPipeline& p, PyModel& model, const py::object& frame, const std::vector<std::string>& outputs,
                       float exposure_ev, const std::string& curve, bool srgb, bool stats) {
            p.device->get("Pipeline.run");
            model.device->get("Pipeline.run: model");
            const Wanted w = wanted_outputs(outputs);
            const ngi::ToneMapOptions tm = tonemap_options(exposure_ev, curve, srgb);
            ngi::PreprocessStats st;
            ngi::FrameImages r;
            if (py::isinstance<py::dict>(frame)) {
                ngi::FrameDesc desc;
                int n = 0;
                const std::vector<float> planes = planes_from_dict(frame.cast<py::dict>(), desc, n);
                py::gil_scoped_release release;
                r = p.pipeline.run(model.model, planes.data(), planes.size() * sizeof(float), desc, w.lightmap,
                                   w.final_image, w.display, tm, stats ? &st : nullptr);
            } else {
                std::shared_ptr<ngi::Frame> fr;
                if (py::isinstance<ngi::Frame>(frame)) fr = frame.cast<std::shared_ptr<ngi::Frame>>();
                else {
                    const std::string path = path_string(frame, "Pipeline.run: frame (a Frame, a dict or a path)");
                    py::gil_scoped_release release;
                    fr = std::make_shared<ngi::Frame>(ngi::read_frame(path));
                }
                py::gil_scoped_release release;
                r = p.pipeline.run(model.model, *fr, w.lightmap, w.final_image, w.display, tm, stats ? &st : nullptr);
            }
            py::dict out = outputs_dict(w, std::move(r));
            if (stats) out["stats"] = stats_dict(st);
            return out;
        }, py::arg("model"), py::arg("frame"), py::arg("outputs") = std::vector<std::string>{"lightmap", "final"},
           py::arg("exposure_ev") = 0.0f, py::arg("curve") = "aces", py::arg("srgb") = true, py::arg("stats") = false,
           R"doc(
One frame through the whole pipeline: one upload of its planes, one download of the outputs. `frame` is a Frame,
a frame folder path, or a dict of [faces, C, N, N] arrays (faces 6, or 1 for a single-view model; see
Frame.from_dict), packed straight into the device layout. Returns a dict with the outputs asked for, each
[3, N, N] float32: 'lightmap' (linear HDR), 'final' (lightmap x albedo + emission + env, linear), 'display'
(tone-mapped to [0, 1]: exposure_ev, curve 'aces' | 'reinhard' | 'clamp', srgb); with stats=True also 'stats'
(non-finite values replaced per feature, sky normals, far depths).)doc")
        .def("run_images", [](PyPipeline& p, PyModel& model, const py::dict& images, const py::object& look,
                              const py::object& up, const std::vector<std::string>& outputs, float exposure_ev,
                              const std::string& curve, bool srgb, bool stats, bool timings) {
            p.device->get("Pipeline.run_images");
            model.device->get("Pipeline.run_images: model");
            const Wanted w = wanted_outputs(outputs);
            const ngi::ToneMapOptions tm = tonemap_options(exposure_ev, curve, srgb);
            ngi::FrameInputs in;
            in.look = vec3(look, "Pipeline.run_images: look");
            in.up = vec3(up, "Pipeline.run_images: up");
            std::vector<py::array> keep;
            for (auto item : images) {
                if (!py::isinstance<py::tuple>(item.first) || py::len(item.first) != 2)
                    throw py::value_error("Pipeline.run_images: keys are (face, feature) tuples, e.g. ('front', 'albedo')");
                const py::tuple key = item.first.cast<py::tuple>();
                const std::string face = py::str(key[0]), feature = py::str(key[1]);
                const ngi::Face f = ngi::face_from_name(face);
                int k = -1;
                for (ngi::Feature ft : kFeatures)
                    if (feature == ngi::feature_name(ft)) k = int(ft);
                if (k < 0) throw py::value_error("Pipeline.run_images: unknown feature '" + feature + "'");
                in.at(f, ngi::Feature(k)) =
                    image_desc_from(item.second, "Pipeline.run_images: images[('" + face + "', '" + feature + "')]", keep);
            }
            ngi::PreprocessStats st;
            ngi::FrameTimings tt;
            ngi::FrameImages r;
            {
                py::gil_scoped_release release;
                r = p.pipeline.run(model.model, in, w.lightmap, w.final_image, w.display, tm, stats ? &st : nullptr,
                                   timings ? &tt : nullptr);
            }
            py::dict out = outputs_dict(w, std::move(r));
            if (stats) out["stats"] = stats_dict(st);
            if (timings) {
                py::dict t;
                t["gather_ms"] = tt.gather_ms;
                t["input_ms"] = tt.input_ms;
                t["network_ms"] = tt.network_ms;
                t["outputs_ms"] = tt.outputs_ms;
                out["timings"] = t;
            }
            return out;
        }, py::arg("model"), py::arg("images"), py::arg("look") = std::vector<float>{0, 0, -1},
           py::arg("up") = std::vector<float>{0, 1, 0},
           py::arg("outputs") = std::vector<std::string>{"lightmap", "final"}, py::arg("exposure_ev") = 0.0f,
           py::arg("curve") = "aces", py::arg("srgb") = true, py::arg("stats") = false, py::arg("timings") = false,
           R"doc(
One frame from render targets as an engine holds them (image descriptors, ngi/image_desc.hpp), without repacking:
`images` maps (face, feature) -> a NumPy array [N, N] or [N, N, C] (float32, float16, uint8 (unorm), uint16
(unorm) or int16 (snorm); C up to 4, the first 3 read, 1 for depth; any positive strides, e.g. a channel slice or a
padded pitch) or a dict {"array": a, "srgb": bool (uint8 sRGB albedo), "scale": s, "bias": b (value = stored x s + b,
e.g. 2, -1 for unorm normals), "bottom_up": bool (OpenGL row order), "format": "r11g11b10f" or "rgb10a2" (a uint32
[N, N] array of packed words; or any format name for an array of its value size), "normal": "octahedral" (2 channels
in [-1, 1]), "normal_to_world": a 3 x 3 row-major rotation (view-space normals), "depth": "perspective" with "near",
"far" (metres; far=inf for an infinite far plane) and "reversed_z": bool (a depth attachment as rendered)}. Faces 'front', 'back', 'left', 'right', 'up', 'down' (a single-view model reads 'front');
features 'albedo', 'normal', 'depth', 'direct' and optionally 'emission', 'env' on every face or none. Outputs as
run(); timings=True adds 'timings' (ms per stage: gather, input, network, outputs).)doc")
        .def("enqueue", [](PyPipeline& p, PyModel& model, const py::object& planes, const py::object& look,
                           const py::object& up, int faces, bool has_emission, bool has_env, const py::object& lightmap,
                           const py::object& final_image, const py::object& display) {
            ngi::FrameDesc desc;
            desc.faces = faces;
            desc.has_emission = has_emission;
            desc.has_env = has_env;
            desc.look = vec3(look, "Pipeline.enqueue: look");
            desc.up = vec3(up, "Pipeline.enqueue: up");
            const ngi::DeviceBuffer in = device_buffer(p.device, planes, "Pipeline.enqueue: planes");
            ngi::FrameOutputs out;
            if (!lightmap.is_none()) out.lightmap = device_buffer(p.device, lightmap, "Pipeline.enqueue: lightmap");
            if (!final_image.is_none()) out.final_image = device_buffer(p.device, final_image, "Pipeline.enqueue: final");
            if (!display.is_none()) out.display = device_buffer(p.device, display, "Pipeline.enqueue: display");
            py::gil_scoped_release release;
            p.pipeline.enqueue(model.model, in, desc, out);
        }, py::arg("model"), py::arg("planes"), py::arg("look"), py::arg("up"), py::arg("faces") = 6,
           py::arg("has_emission") = true, py::arg("has_env") = true, py::arg("lightmap") = py::none(),
           py::arg("final") = py::none(), py::arg("display") = py::none(), R"doc(
Device in, device out, asynchronous, no host transfer: `planes` (a DeviceBuffer or pyopencl Buffer) holds the
frame as float32 [faces][16][N][N] (planes: albedo 0-2, normal 3-5, depth 6, direct 7-9, emission 10-12, env
13-15); each output buffer given receives [3][N][N] float32. Returns once enqueued.)doc")
        .def("network_input", [](PyPipeline& p, const ngi::Frame& frame, const PyModel* model, bool single_view,
                                 const PyModel* ssgi) {
            p.device->get("Pipeline.network_input");
            const ngi::ModelConfig config = merge_config(model, single_view, ssgi);
            ngi::Tensor t = [&] {
                py::gil_scoped_release release;
                return p.pipeline.network_input(frame, config);
            }();
            return from_tensor(std::move(t));
        }, py::arg("frame"), py::arg("model") = py::none(), py::arg("single_view") = false,
           py::arg("ssgi") = py::none(), R"doc(
The generator's input for a frame (what `ngi merge` writes as input.npy): [1, 12, 2N, 4N] (surround) or
[1, 10, N, N] (single view), channels as surround_input_channels() / single_view_input_channels(), values in the
input range. With a model, its config decides; without one, the default surround layout (single_view=True: the
front view only) and range [-1, 1]. ssgi=<a family ssgi model>: the [1, 13, N, N] input of a network that corrects
that rung (output_mode "ssgi_residual"; ssgi_residual_input_channels(); the frame needs the faces the rung gathers
from).)doc")
        .def("encode_lightmap", [](PyPipeline& p, const py::object& lightmap, const PyModel* model) {
            ngi::Image img = to_image(lightmap, "Pipeline.encode_lightmap: lightmap");
            p.device->get("Pipeline.encode_lightmap");
            return from_tensor(p.pipeline.encode_lightmap(img, merge_config(model, false, nullptr)));
        }, py::arg("lightmap"), py::arg("model") = py::none(),
           "A linear lightmap [3, H, W] as a training target [1, 3, H, W] in the output range (the model's, else "
           "[-1, 1]): what `ngi merge` writes as target.npy for the frame's reference.")
        .def("front_lightmap", [](PyPipeline& p, const py::object& output, const PyModel& model,
                                  const py::object& frame) {
            FloatArray a = float_array(output, "Pipeline.front_lightmap: output");
            expect_ndim(a, {4}, "Pipeline.front_lightmap: output", "[1, 3, H, W]");
            ngi::Tensor t(std::vector<int>(a.shape(), a.shape() + 4));
            std::memcpy(t.data.data(), a.data(), t.data.size() * sizeof(float));
            p.device->get("Pipeline.front_lightmap");
            if (frame.is_none()) return from_image(p.pipeline.front_lightmap(t, model.model.config()));
            std::shared_ptr<ngi::Frame> fr;
            if (py::isinstance<ngi::Frame>(frame)) fr = frame.cast<std::shared_ptr<ngi::Frame>>();
            else fr = std::make_shared<ngi::Frame>(
                     ngi::read_frame(path_string(frame, "Pipeline.front_lightmap: frame (a Frame, a path or None)")));
            return from_image(p.pipeline.front_lightmap(t, model.model.config(), *fr));
        }, py::arg("output"), py::arg("model"), py::arg("frame") = py::none(), R"doc(
The front view's linear lightmap [3, N, N] from a generator output [1, 3, 2N, 4N] or [1, 3, N, N]. A model with
output_mode "indirect" predicts indirect light only: its lightmap adds the frame's front direct light, so it needs
`frame` (a Frame or a frame folder path; ngi.InputError without it). A "lightmap" model does not read the frame.)doc")
        .def("global_view", [](PyPipeline& p, const ngi::Frame& frame, const std::string& feature) {
            for (ngi::Feature f : kFeatures)
                if (feature == ngi::feature_name(f)) {
                    p.device->get("Pipeline.global_view");
                    return from_image(p.pipeline.global_view(frame, f));
                }
            throw py::value_error("Pipeline.global_view: unknown feature '" + feature + "'");
        }, py::arg("frame"), py::arg("feature"), "One raw feature of the six faces merged into [C, 2N, 4N].")
        .def_property_readonly("coord_map", [](const PyPipeline& p) {
            return from_image(ngi::Image(p.pipeline.coord_map()));
        }, "The (phi, theta) coordinate map [2, 2N, 4N], values in [0, 1].")
        .def("tonemap", [](PyPipeline& p, const py::object& image, float exposure_ev, const std::string& curve,
                           bool srgb) {
            ngi::Image img = to_image(image, "Pipeline.tonemap: image");
            p.device->get("Pipeline.tonemap");
            return from_image(p.pipeline.tonemap(img, tonemap_options(exposure_ev, curve, srgb)));
        }, py::arg("image"), py::arg("exposure_ev") = 0.0f, py::arg("curve") = "aces", py::arg("srgb") = true,
           "A linear image to display values in [0, 1].");

    py::class_<PyDisplayView, std::shared_ptr<PyDisplayView>>(m, "DisplayView", R"doc(
The front view's GI at display resolution, stable from frame to frame (ngi/display.hpp, docs/CONVENTIONS.md
section 20): the pipeline's N x N lightmap minus the frame's direct light is upsampled to the display's S x S pixels
(upsampler "jbu": joint bilateral, guided by the display's normals and positions; "bilinear"), accumulated over
frames (temporal=True: the previous result reprojected with the camera motion and the display's depth, rejected
where the point was hidden, clamped to this frame's light, blended with weight `blend`), and composed with the
display's direct light, albedo and emission. One object per view; reset() after a cut.
DisplayView(device, size, upsampler="jbu", temporal=True, blend=0.2, clip_margin=0.25, sigma_spatial=0.75,
normal_power=32, sigma_plane=0.1, radius=2, depth_rel=0.02, depth_abs=0.05).)doc")
        .def(py::init([](const DeviceRef& device, int size, const std::string& upsampler, bool temporal, float blend,
                         float clip_margin, float sigma_spatial, float normal_power, float sigma_plane, int radius,
                         float depth_rel, float depth_abs) {
                 const ngi::Device& dev = device->get("DisplayView");
                 ngi::DisplaySettings s;
                 s.upsampler = ngi::display_upsampler_from_name(upsampler);
                 s.temporal = temporal;
                 s.blend = blend;
                 s.clip_margin = clip_margin;
                 s.sigma_spatial = sigma_spatial;
                 s.normal_power = normal_power;
                 s.sigma_plane = sigma_plane;
                 s.radius = radius;
                 s.depth_rel = depth_rel;
                 s.depth_abs = depth_abs;
                 py::gil_scoped_release release;
                 return std::make_shared<PyDisplayView>(PyDisplayView{device, ngi::DisplayView(dev, size, s)});
             }),
             py::arg("device"), py::arg("size"), py::arg("upsampler") = "jbu", py::arg("temporal") = true,
             py::arg("blend") = 0.2f, py::arg("clip_margin") = 0.25f, py::arg("sigma_spatial") = 0.75f,
             py::arg("normal_power") = 32.0f, py::arg("sigma_plane") = 0.1f, py::arg("radius") = 2,
             py::arg("depth_rel") = 0.02f, py::arg("depth_abs") = 0.05f)
        .def_property_readonly("size", [](const PyDisplayView& v) { return v.view.size(); })
        .def("reset", [](PyDisplayView& v) { v.view.reset(); }, "Forget the history: the next frame stands alone.")
        .def("run", [](PyDisplayView& v, const py::object& low, const py::object& lightmap, const py::object& display,
                       const py::object& position, const std::vector<std::string>& outputs, float exposure_ev,
                       const std::string& curve, bool srgb, bool stats, bool timings) {
            v.device->get("DisplayView.run");
            const Wanted w = wanted_outputs(outputs);
            const ngi::ToneMapOptions tm = tonemap_options(exposure_ev, curve, srgb);
            const auto lo = frame_arg(low, "DisplayView.run: low (a Frame or a frame folder path)");
            const auto hi = frame_arg(display, "DisplayView.run: display (a Frame or a frame folder path)");
            const ngi::Image lm = to_image(lightmap, "DisplayView.run: lightmap");
            const glm::vec3 pos = vec3(position, "DisplayView.run: position");
            ngi::DisplayStats st;
            ngi::DisplayTimings tt;
            ngi::FrameImages r;
            {
                py::gil_scoped_release release;
                r = v.view.run(*lo, lm, *hi, pos, w.lightmap, w.final_image, w.display, tm, stats ? &st : nullptr,
                               timings ? &tt : nullptr);
            }
            py::dict out = outputs_dict(w, std::move(r));
            if (stats) {
                py::dict d;
                d["jbu_fallbacks"] = st.jbu_fallbacks;
                d["disoccluded"] = st.disoccluded;
                d["clipped"] = st.clipped;
                d["history_used"] = st.history_used;
                out["stats"] = d;
            }
            if (timings) {
                py::dict t;
                t["geometry_ms"] = tt.geometry_ms;
                t["upsample_ms"] = tt.upsample_ms;
                t["temporal_ms"] = tt.temporal_ms;
                t["outputs_ms"] = tt.outputs_ms;
                out["timings"] = t;
            }
            return out;
        }, py::arg("low"), py::arg("lightmap"), py::arg("display"), py::arg("position"),
           py::arg("outputs") = std::vector<std::string>{"lightmap", "final"}, py::arg("exposure_ev") = 0.0f,
           py::arg("curve") = "aces", py::arg("srgb") = true, py::arg("stats") = false, py::arg("timings") = false,
           R"doc(
One frame at display resolution: `low` the frame the pipeline ran (a Frame or folder; its front normal, depth and
direct light are read), `lightmap` the pipeline's lightmap of it [3, N, N], `display` a frame of face size S (its
front albedo, normal, depth, direct; emission and env optional) with the same look and up, `position` the camera
centre in world metres (render.json's camera.position). Returns the outputs asked for, each [3, S, S] float32
('lightmap', 'final', 'display' as Pipeline.run); stats=True adds 'stats' (jbu_fallbacks, disoccluded, clipped,
history_used), timings=True 'timings' (ms: geometry, upsample, temporal, outputs).)doc");
}

}  // namespace ngi_py
