// ngi.Model: a model file (generator, mlp, voxel_sh, neural_gi or an imported graph) loaded on a device, run on NumPy arrays or on device buffers.
#include <nlohmann/json.hpp>

#include "common.hpp"
#include "model_ref.hpp"
#include "ngi/ao.hpp"
#include "ngi/warmup.hpp"

namespace ngi_py {

namespace {

py::dict config_dict(const ngi::ModelConfig& c) {
    py::dict d;
    d["family"] = c.family;
    d["input_nc"] = c.input_nc;
    d["output_nc"] = c.output_nc;
    // The family's traits (ngi/model.hpp): what to choose by instead of the family's name.
    d["input"] = c.input == ngi::ModelInput::items ? "items" : "image";
    d["has_network"] = c.has_network;
    d["output_keeps_size"] = c.output_keeps_size;
    // The sections of the public config a model has (which fields to show, not what to do with it): a family with
    // none (pixel_cnn, ssgi) shows none.
    if (!c.voxel_sh.architecture.empty()) {  // voxel_sh's parser sets its required architecture
        d["architecture"] = c.voxel_sh.architecture;
        d["grid"] = py::make_tuple(c.voxel_sh.grid[0], c.voxel_sh.grid[1], c.voxel_sh.grid[2]);
    }
    if (c.family == "graph") d["layout"] = c.graph.layout;  // ModelConfig::graph, that family's own section
    if (c.unet.ngf > 0) {  // ModelConfig::unet: a U-Net (the generators; neural_gi's buffer network)
        d["ngf"] = c.unet.ngf;
        d["num_downs"] = c.unet.num_downs;
        d["bn_mode"] = c.unet.bn_mode;
        d["dropout"] = c.unet.dropout;
    }
    d["input_layout"] = c.input_layout;
    d["input_range"] = py::make_tuple(c.input_range[0], c.input_range[1]);
    d["output_range"] = py::make_tuple(c.output_range[0], c.output_range[1]);
    d["output_mode"] = c.output_mode;
    d["metadata"] = py::module_::import("json").attr("loads")(c.json.empty() ? std::string("{}") : c.json);
    return d;
}

ngi::ModelOptions options(const std::optional<std::string>& bn_mode, const std::optional<std::string>& dropout,
                          const std::optional<std::string>& mlp_path) {
    ngi::ModelOptions o;
    if (bn_mode) o.bn_mode = *bn_mode;
    if (dropout) o.dropout = *dropout;
    if (mlp_path) o.mlp_path = *mlp_path;
    return o;
}

// [1, C, H, W] straight from the array's memory into a device buffer and back into the result's memory: no host
// copy on either side. The buffers are kept for the next call of the same size.
py::array_t<float> run_nchw(PyModel& pm, const FloatArray& x) {
    const ngi::ModelConfig& c = pm.model.config();
    const int h = int(x.shape(2)), w = int(x.shape(3));
    const std::size_t in_bytes = std::size_t(x.size()) * sizeof(float);
    const std::size_t out_bytes = std::size_t(c.output_nc) * std::size_t(h) * std::size_t(w) * sizeof(float);
    const ngi::Device& dev = pm.device->get("Model.run");
    FloatArray y(std::vector<py::ssize_t>{1, c.output_nc, h, w});
    float* dst = y.mutable_data();
    {
        py::gil_scoped_release release;
        if (!pm.input || pm.input.bytes() != in_bytes) pm.input = ngi::DeviceBuffer::allocate(dev, in_bytes);
        if (!pm.output || pm.output.bytes() != out_bytes) pm.output = ngi::DeviceBuffer::allocate(dev, out_bytes);
        pm.input.upload(x.data(), in_bytes);
        pm.model.enqueue(pm.input, pm.output, h, w);
        pm.output.download(dst, out_bytes);
        pm.sanitized = pm.model.sanitized_inputs();
    }
    return y;
}

}  // namespace

// An ngi.AoNetwork: the network plus the device state it was made on (to refuse use after close()).
struct PyAo {
    DeviceRef device;
    ngi::AoNetwork net;
};

void register_model(py::module_& m) {
    m.def("resolve_model", [](const py::object& name) { return ngi::resolve_model(path_string(name, "resolve_model")); },
          py::arg("name_or_path"), R"doc(
The file a model name means ("surround" -> .../share/ngi/models/surround.safetensors); a path (an existing file, or
anything with a '/' or ending in .safetensors) comes back unchanged. An unknown name raises ngi.InputError listing
the folders searched and the known names. Folders: $NGI_MODEL_PATH (':'-separated), the installed models, the
source tree's models/ (ngi/model.hpp "Shipped models by name").)doc");
    m.def("model_names", [] {
        py::dict d;
        for (const auto& [name, file] : ngi::model_names()) d[py::str(name)] = file;
        return d;
    }, "Every known model name -> its file (see resolve_model).");
    m.def("model_search_path", [] { return ngi::model_search_path(); },
          "The existing folders model names are looked up in, in order (see resolve_model).");
    m.def("program_cache_dir", [] { return ngi::program_cache_dir().string(); },
          "ngi's program cache folder: $NGI_CACHE_DIR, else $XDG_CACHE_HOME/ngi, else ~/.cache/ngi (see warm_up).");
    m.def("warm_up", [](const std::shared_ptr<PyModel>& model, int n, int display) {
        const ngi::Device& device = model->device->get("warm_up");
        ngi::WarmUpReport r;
        {
            py::gil_scoped_release release;
            r = ngi::warm_up(device, model->model, n, display);
        }
        py::dict d;
        d["cache_dir"] = r.cache_dir;
        d["programs_built"] = r.programs_built;
        d["programs_from_cache"] = r.programs_from_cache;
        d["first_frame_ms"] = r.first_frame_ms;
        d["second_frame_ms"] = r.second_frame_ms;
        return d;
    }, py::arg("model"), py::arg("n") = 64, py::arg("display") = 0, R"doc(
Cold start (ngi/warmup.hpp): runs the model (a frame rung: an image generator whose input the surround pipeline
makes, or an ssgi rung; config["input"] == "image" or not config["has_network"]) twice on a synthetic frame at face size n, and through a display view of display x display pixels when display > 0, so that
every OpenCL program and work-group size its frames need is built into the program caches (program_cache_dir(), and
$POCL_CACHE_DIR on PoCL): a later process starts fast. Returns {cache_dir, programs_built, programs_from_cache,
first_frame_ms, second_frame_ms}. Raises ngi.InputError for another model or a cache folder it cannot write.)doc");
    py::class_<PyModel, std::shared_ptr<PyModel>>(m, "Model", R"doc(
A model file loaded on a device: a generator (pix2pix_unet, deepillumination), an mlp or a voxel_sh field network
(docs/MODEL_FORMAT.md).

Model(device, path, bn_mode=None, dropout=None, mlp_path=None): `path` is a model file or a shipped model's name
("surround", "ao_bunny_32x16", ...; ngi.model_names() lists them, ngi.resolve_model() says which file a name
means). The options override the file's settings
("running" | "per_image"; "off" | "seeded"; "fused" | "dense"). Weights are packed and uploaded once; the graph for
each input size is built on first use.)doc")
        .def(py::init([](const DeviceRef& device, const py::object& path, std::optional<std::string> bn_mode,
                         std::optional<std::string> dropout, std::optional<std::string> mlp_path) {
                 const std::string p = ngi::resolve_model(path_string(path, "Model: path"));
                 const ngi::Device& dev = device->get("Model");
                 const ngi::ModelOptions o = options(bn_mode, dropout, mlp_path);
                 py::gil_scoped_release release;
                 return std::make_shared<PyModel>(PyModel{device, ngi::Model::load(dev, p, o), p, 0, {}, {}});
             }),
             py::arg("device"), py::arg("path"), py::arg("bn_mode") = py::none(), py::arg("dropout") = py::none(),
             py::arg("mlp_path") = py::none())
        .def_property_readonly("config", [](const PyModel& pm) { return config_dict(pm.model.config()); },
                               "The architecture (family, channel counts, ranges, ...), the family's traits "
                               "(input: 'image' or 'items', what run() takes; has_network: False for an ssgi rung; "
                               "output_keeps_size: False when the network sizes its output) and the file's metadata.")
        .def_property_readonly("path", [](const PyModel& pm) { return pm.path; })
        .def_property_readonly("output_mode", [](const PyModel& pm) { return pm.model.config().output_mode; },
                               "What the decoded output is: 'lightmap' (the front view's direct + indirect light; "
                               "the default) or 'indirect' (indirect light only; the pipeline adds the frame's "
                               "front direct light).")
        .def_property_readonly("sanitized_inputs", [](const PyModel& pm) { return pm.sanitized; },
                               "Input values the last run() replaced (NaN -> 0; +-Inf and values far outside the "
                               "input range -> its nearer end).")
        .def("run", [](PyModel& pm, const py::object& input) -> py::array_t<float> {
            FloatArray x = float_array(input, "Model.run: input");
            const ngi::ModelConfig& c = pm.model.config();
            // Per-item networks take point lists [N, C] too (voxel_sh: [V, 10], one scene's voxels).
            const bool items = c.input == ngi::ModelInput::items;
            expect_ndim(x, items ? std::initializer_list<int>{2, 4} : std::initializer_list<int>{4},
                        "Model.run: input", items ? "[1, C, H, W] or [N, C]" : "[1, C, H, W]");
            if (x.ndim() == 4) {
                if (x.shape(0) != 1 || x.shape(1) != c.input_nc)
                    throw py::value_error("Model.run: input: expected [1, " + std::to_string(c.input_nc) +
                                          ", H, W] for " + pm.path + ", got [" + std::to_string(x.shape(0)) + ", " +
                                          std::to_string(x.shape(1)) + ", ...]");
                // A network that may resample (an imported graph: its output's size is its own) goes through the
                // library's Tensor, which is sized from the network.
                if (c.output_keeps_size) return run_nchw(pm, x);
            }
            // [N, C] points: channels last, so the library transposes; one copy into its Tensor.
            std::vector<int> shape;
            for (py::ssize_t i = 0; i < x.ndim(); ++i) shape.push_back(int(x.shape(i)));
            ngi::Tensor t(shape);
            std::memcpy(t.data.data(), x.data(), t.data.size() * sizeof(float));
            ngi::RunInfo info;
            pm.device->get("Model.run");
            ngi::Tensor y = [&] {
                py::gil_scoped_release release;
                return pm.model.run(t, &info);
            }();
            pm.sanitized = info.sanitized_inputs;
            return from_tensor(std::move(y));
        }, py::arg("input"), R"doc(
Run the model on a float array and return a new float32 array.
Generators: [1, input_nc, H, W] -> [1, output_nc, H, W] (H, W multiples of 2^num_downs).
mlp: per pixel [1, input_nc, H, W] -> [1, output_nc, H, W], or per point [N, input_nc] -> [N, output_nc].
A C-contiguous float32 [1, C, H, W] array goes to the device without a host copy; other dtypes/orders are
converted first. The GIL is released while the device works.)doc")
        .def("enqueue", [](PyModel& pm, const py::object& input, const py::object& output, int height, int width) {
            const ngi::DeviceBuffer in = device_buffer(pm.device, input, "Model.enqueue: input");
            const ngi::DeviceBuffer out = device_buffer(pm.device, output, "Model.enqueue: output");
            py::gil_scoped_release release;
            pm.model.enqueue(in, out, height, width);
        }, py::arg("input"), py::arg("output"), py::arg("height"), py::arg("width"), R"doc(
Device in, device out, asynchronous: `input` (a DeviceBuffer or a pyopencl Buffer of the device's context) holds
[1, input_nc, height, width] float32, `output` receives [1, output_nc, height, width]. Returns once enqueued;
Device.finish() waits (or pyopencl's queue.finish() on a Device.from_pyopencl device).)doc")
        .def("__repr__", [](const PyModel& pm) {
            const auto& c = pm.model.config();
            return "<ngi.Model " + c.family + " " + std::to_string(c.input_nc) + " -> " + std::to_string(c.output_nc) +
                   " from '" + pm.path + "'>";
        });

    py::class_<PyAo, std::shared_ptr<PyAo>>(m, "AoNetwork", R"doc(
Seed 001's ambient-occlusion MLP (docs/RESULTS_AO.md): AoNetwork(device, path) (a file or a shipped model's name,
e.g. "ao_bunny_32x16"); run(normals [3, H, W], radius_px=-1) -> accessibility [1, H, W] in [0, 1] (1 = open; radius -1: the training radius scaled to H).)doc")
        .def(py::init([](const DeviceRef& device, const py::object& path) {
                 const std::string p = ngi::resolve_model(path_string(path, "AoNetwork: path"));
                 const ngi::Device& dev = device->get("AoNetwork");
                 py::gil_scoped_release release;
                 return std::make_shared<PyAo>(PyAo{device, ngi::AoNetwork::load(dev, p)});
             }),
             py::arg("device"), py::arg("path"))
        .def_property_readonly("normals", [](const PyAo& a) { return a.net.normals(); },
                               "'smooth' or 'face': the normals it was trained on.")
        .def("radius_for", [](const PyAo& a, int height) { return a.net.radius_for(height); }, py::arg("height"))
        .def("run", [](PyAo& a, const py::object& normals, float radius_px) {
            a.device->get("AoNetwork.run");
            ngi::Image n = to_image(normals, "AoNetwork.run: normals");
            if (n.channels != 3) throw py::value_error("AoNetwork.run: normals: expected [3, H, W]");
            ngi::Image ao = [&] {
                py::gil_scoped_release release;
                return a.net.run(n, radius_px);
            }();
            return from_image(std::move(ao));
        }, py::arg("normals"), py::arg("radius_px") = -1.0f);
}

}  // namespace ngi_py
