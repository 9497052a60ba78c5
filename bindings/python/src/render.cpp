// ngi.Scene and ngi.Renderer: the voxel scenes and the OpenCL path tracer (docs/RENDERER.md).
#include "common.hpp"
#include "ngi/camera_path.hpp"
#include "ngi/dataset.hpp"
#include "ngi/render.hpp"
#include "ngi/scene.hpp"
#include "ngi/voxel_field.hpp"
#include "ngi/voxel_gi.hpp"

namespace ngi_py {

namespace {

struct PyRenderer {
    DeviceRef device;
    std::shared_ptr<const ngi::VoxelScene> scene;
    ngi::Renderer renderer;
};

// The pose of frame `frame` of the dataset camera path with `frames` frames, or an explicit one.
ngi::CameraPose pose_of(const ngi::VoxelScene& scene, const py::object& position, const py::object& look,
                        const py::object& up, int frame, int frames) {
    if (frames < 1 || frame < 0 || frame >= frames)
        throw py::value_error("Renderer: frame " + std::to_string(frame) + " is not in 0 .. frames - 1 = " +
                              std::to_string(frames - 1));
    if (position.is_none()) return ngi::dataset_camera_path(scene, frames, 25).at(float(frame));
    ngi::CameraPose p;
    p.position = vec3(position, "Renderer: position");
    if (!look.is_none()) p.look = vec3(look, "Renderer: look");
    if (!up.is_none()) p.up = vec3(up, "Renderer: up");
    return p;
}

ngi::RenderSettings settings(const ngi::VoxelScene& scene, int n, int spp, int feature_spp, int bounces,
                             bool reference, const std::optional<std::uint32_t>& seed, int frame) {
    if (n < 1 || n > 8192) throw py::value_error("Renderer: n must be in 1 .. 8192");
    if (spp < 1 || feature_spp < 1) throw py::value_error("Renderer: spp and feature_spp must be >= 1");
    if (bounces < 0 || bounces > 1000) throw py::value_error("Renderer: bounces must be in 0 .. 1000");
    ngi::RenderSettings rs;
    rs.n = n;
    rs.reference_spp = spp;
    rs.feature_spp = feature_spp;
    rs.max_bounces = bounces;
    rs.reference = reference;
    rs.seed = seed ? *seed : ngi::dataset_frame_seed(scene.name, frame);  // `ngi render --frame K`'s seed
    return rs;
}

// A baked per-surface-voxel lighting: the scene's surface voxels at one time of day (their probe points), the
// VoxelGi that shades frames from a per-voxel field, and the renderer that path-traces the field.
struct PyVoxelProbes {
    std::shared_ptr<PyRenderer> renderer;
    ngi::Lighting lighting;
    ngi::SurfaceVoxels voxels;
    ngi::VoxelGi gi;
};

}  // namespace

void register_render(py::module_& m) {
    py::class_<ngi::VoxelScene, std::shared_ptr<ngi::VoxelScene>>(m, "Scene", R"doc(
A voxel scene: Scene("room:seed=3") for a procedural family (room, street, cave, backlit, bleed, sculpture) or
Scene("file.vox") for a MagicaVoxel file. 1 block = 1 metre, +y up (docs/RENDERER.md).)doc")
        .def(py::init([](const py::object& spec) {
                 const std::string s = py::isinstance<py::str>(spec) ? spec.cast<std::string>()
                                                                      : path_string(spec, "Scene: spec");
                 py::gil_scoped_release release;
                 return std::make_shared<ngi::VoxelScene>(ngi::make_scene(s));
             }),
             py::arg("spec"))
        .def_readonly("name", &ngi::VoxelScene::name)
        .def_property_readonly("size", [](const ngi::VoxelScene& s) { return py::make_tuple(s.size.x, s.size.y, s.size.z); })
        .def_property_readonly("solid_count", &ngi::VoxelScene::solid_count)
        .def_property_readonly("blocks", [](const ngi::VoxelScene& s) {
            // A copy: the scene's storage order x + X (y + Y z) is C order for [Z, Y, X].
            py::array_t<std::uint8_t> a({py::ssize_t(s.size.z), py::ssize_t(s.size.y), py::ssize_t(s.size.x)});
            std::copy(s.voxels.begin(), s.voxels.end(), a.mutable_data());
            return a;
        }, "Material ids [Z, Y, X] (uint8, 0 = air; index [z, y, x] is block (x, y, z), 1 block = 1 metre).")
        .def_readonly("default_time", &ngi::VoxelScene::default_time, "Hours of the day renders use by default.")
        .def_static("families", &ngi::scene_families, "The procedural scene families.")
        .def("__repr__", [](const ngi::VoxelScene& s) {
            return "<ngi.Scene '" + s.name + "' " + std::to_string(s.size.x) + " x " + std::to_string(s.size.y) +
                   " x " + std::to_string(s.size.z) + ">";
        });

    py::class_<PyRenderer, std::shared_ptr<PyRenderer>>(m, "Renderer", R"doc(
The OpenCL voxel path tracer on one scene: Renderer(device, scene). Rendering is deterministic (same scene, pose,
time, settings and seed: same image). A pose is either frame `frame` of the scene's dataset camera path of
`frames` frames (what `ngi render --frame K` renders) or an explicit position (+ look, up).)doc")
        .def(py::init([](const DeviceRef& device, std::shared_ptr<ngi::VoxelScene> scene) {
                 const ngi::Device& dev = device->get("Renderer");
                 py::gil_scoped_release release;
                 return std::make_shared<PyRenderer>(PyRenderer{device, scene, ngi::Renderer(dev, *scene)});
             }),
             py::arg("device"), py::arg("scene"))
        .def("render", [](PyRenderer& r, int n, int spp, int feature_spp, int bounces, bool reference,
                          std::optional<float> time, int frame, int frames, const py::object& position,
                          const py::object& look, const py::object& up, std::optional<std::uint32_t> seed) {
            r.device->get("Renderer.render");
            const ngi::VoxelScene& s = *r.scene;
            const ngi::CameraPose pose = pose_of(s, position, look, up, frame, frames);
            const ngi::RenderSettings rs = settings(s, n, spp, feature_spp, bounces, reference, seed, frame);
            const float hours = time ? *time : s.default_time;
            if (!(hours >= 0.0f && hours <= 48.0f)) throw py::value_error("Renderer.render: time must be in 0 .. 48 hours");
            py::gil_scoped_release release;
            return std::make_shared<ngi::Frame>(r.renderer.render(pose, ngi::lighting_at(hours, s.sun_azimuth), rs));
        }, py::arg("n") = 128, py::arg("spp") = 64, py::arg("feature_spp") = ngi::kEngineFeatureSpp, py::arg("bounces") = 8,
           py::arg("reference") = true, py::arg("time") = py::none(), py::arg("frame") = 0, py::arg("frames") = 100,
           py::arg("position") = py::none(), py::arg("look") = py::none(), py::arg("up") = py::none(),
           py::arg("seed") = py::none(),
           "A Frame: the six faces' features and (reference=True) the front view's path-traced reference lighting.")
        .def("render_ao", [](PyRenderer& r, int n, int rays, float max_distance, int frame, int frames,
                             const py::object& position, const py::object& look, const py::object& up,
                             std::uint32_t seed) {
            r.device->get("Renderer.render_ao");
            const ngi::CameraPose pose = pose_of(*r.scene, position, look, up, frame, frames);
            ngi::RenderSettings rs = settings(*r.scene, n, 1, 1, 0, false, seed, frame);
            if (rays < 1) throw py::value_error("Renderer.render_ao: rays must be >= 1");
            ngi::Image ao = [&] {
                py::gil_scoped_release release;
                return r.renderer.render_ao(pose, rs, rays, max_distance);
            }();
            return from_image(std::move(ao));
        }, py::arg("n") = 256, py::arg("rays") = 256, py::arg("max_distance") = 4.0f, py::arg("frame") = 0,
           py::arg("frames") = 100, py::arg("position") = py::none(), py::arg("look") = py::none(),
           py::arg("up") = py::none(), py::arg("seed") = 1,
           "Ambient occlusion of the front view [1, N, N]: the fraction of cosine-weighted rays that travel max_distance "
           "metres unblocked (1 = open; 1 where no surface is seen).")
        .def("render_geometry", [](PyRenderer& r, int n, float sigma, int frame, int frames, const py::object& position,
                                   const py::object& look, const py::object& up) {
            r.device->get("Renderer.render_geometry");
            const ngi::CameraPose pose = pose_of(*r.scene, position, look, up, frame, frames);
            ngi::RenderSettings rs = settings(*r.scene, n, 1, 1, 0, false, 1u, frame);
            ngi::Image g = [&] {
                py::gil_scoped_release release;
                return r.renderer.render_geometry(pose, rs, sigma);
            }();
            return from_image(std::move(g));
        }, py::arg("n") = 256, py::arg("sigma") = 1.5f, py::arg("frame") = 0, py::arg("frames") = 100,
           py::arg("position") = py::none(), py::arg("look") = py::none(), py::arg("up") = py::none(),
           "Object-space geometry of the front view [7, N, N]: smooth normal (3), voxel face normal (3), depth (1).")
        .def("project_sh", [](PyRenderer& r, const py::handle& points, std::optional<float> time, int directions,
                              int bounces, std::uint32_t seed, bool indirect) {
            r.device->get("Renderer.project_sh");
            const FloatArray a = float_array(points, "Renderer.project_sh: points");
            if (a.ndim() != 2 || a.shape(1) != 3)
                throw py::value_error("Renderer.project_sh: points must be [P, 3] (metres, inside the scene's grid)");
            std::vector<glm::vec3> p(std::size_t(a.shape(0)));
            for (std::size_t i = 0; i < p.size(); ++i) p[i] = {a.data()[3 * i], a.data()[3 * i + 1], a.data()[3 * i + 2]};
            const float hours = time ? *time : r.scene->default_time;
            if (!(hours >= 0.0f && hours <= 48.0f)) throw py::value_error("Renderer.project_sh: time must be in 0 .. 48 hours");
            if (bounces < 0 || bounces > 1000) throw py::value_error("Renderer.project_sh: bounces must be in 0 .. 1000");
            ngi::VoxelFieldSettings vs;
            vs.directions = directions;
            vs.max_bounces = bounces;
            vs.seed = seed;
            vs.sun_rays = 64;
            ngi::PointSh out = [&] {
                py::gil_scoped_release release;
                return r.renderer.project_points_sh(p, ngi::lighting_at(hours, r.scene->sun_azimuth), vs, indirect);
            }();
            py::dict d;
            d["sh"] = from_vector(std::move(out.sh), {py::ssize_t(p.size()), 3, 9});
            d["seconds"] = out.ms * 1e-3;
            d["rays"] = out.rays;
            return d;
        }, py::arg("points"), py::arg("time") = py::none(), py::arg("directions") = 256, py::arg("bounces") = 8,
           py::arg("seed") = 0u, py::arg("indirect") = true,
           "SH (bands 0-2, [P, 3, 9], docs/CONVENTIONS.md section 14) of the radiance arriving at each point, "
           "`directions` (a perfect square) stratified paths each: with indirect=True only light that has bounced "
           "at least once (an irradiance-probe bake, added to an engine's own direct light). {'sh', 'seconds', "
           "'rays'}; deterministic in `seed`.");

    py::class_<PyVoxelProbes, std::shared_ptr<PyVoxelProbes>>(m, "VoxelProbes", R"doc(
A lighting bake at the scene's surface voxels (seed 004's probe points, docs/VOXEL_FIELD.md): VoxelProbes(renderer,
time=None). bake() path-traces the direct and full lighting at every probe point (irradiance / pi at the voxel's
normal); shade() lights the visible surfaces of a rendered frame's front view from any per-voxel field [V, 3] (each
pixel takes the value of the voxel behind it, docs/VOXEL_LTF.md "Probe shading"): what a baked lightmap at block
resolution gives an engine.)doc")
        .def(py::init([](std::shared_ptr<PyRenderer> r, std::optional<float> time) {
                 const ngi::Device& dev = r->device->get("VoxelProbes");
                 const float hours = time ? *time : r->scene->default_time;
                 if (!(hours >= 0.0f && hours <= 48.0f)) throw py::value_error("VoxelProbes: time must be in 0 .. 48 hours");
                 py::gil_scoped_release release;
                 const ngi::Lighting lighting = ngi::lighting_at(hours, r->scene->sun_azimuth);
                 ngi::SurfaceVoxels voxels = ngi::surface_voxels(dev, *r->scene, lighting);
                 ngi::VoxelGi gi(dev, voxels);
                 return std::make_shared<PyVoxelProbes>(PyVoxelProbes{r, lighting, std::move(voxels), std::move(gi)});
             }),
             py::arg("renderer"), py::arg("time") = py::none())
        .def_property_readonly("count", [](const PyVoxelProbes& p) { return p.voxels.size(); }, "Surface voxels (probes).")
        .def("bake", [](PyVoxelProbes& p, int samples, int bounces, std::uint32_t seed) {
            p.renderer->device->get("VoxelProbes.bake");
            if (samples < 1 || samples > (1 << 20)) throw py::value_error("VoxelProbes.bake: samples must be in 1 .. 2^20");
            if (bounces < 0 || bounces > 1000) throw py::value_error("VoxelProbes.bake: bounces must be in 0 .. 1000");
            ngi::VoxelFieldSettings vs;
            vs.point_samples = samples;
            vs.max_bounces = bounces;
            vs.seed = seed;
            vs.directions = 1;  // the SH projection is not what this bake keeps: one direction, its minimum cost
            vs.sun_rays = 1;
            ngi::VoxelField f = [&] {
                py::gil_scoped_release release;
                return p.renderer->renderer.render_voxel_field(p.voxels, p.lighting, vs);
            }();
            const auto V = py::ssize_t(p.voxels.size());
            py::dict d;
            d["direct"] = from_vector(std::move(f.direct), {V, 3});
            d["lighting"] = from_vector(std::move(f.lighting), {V, 3});
            d["face_lighting"] = from_vector(std::move(f.face_lighting), {V, 6, 3});
            d["seconds"] = f.ms * 1e-3;
            d["rays"] = f.rays;
            return d;
        }, py::arg("samples") = 256, py::arg("bounces") = 8, py::arg("seed") = 0u,
           "Path-trace the lighting at every probe point: {'direct': [V, 3], 'lighting': [V, 3] (direct + `bounces` "
           "bounces), 'face_lighting': [V, 6, 3] (the lighting averaged over each exposed face, faces +x -x +y -y +z "
           "-z; 0 for hidden ones), 'seconds', 'rays'}, `samples` paths per voxel (and per exposed face); "
           "deterministic in `seed`.")
        .def("shade", [](PyVoxelProbes& p, const ngi::Frame& frame, const py::object& position, const py::handle& field) {
            p.renderer->device->get("VoxelProbes.shade");
            const FloatArray a = float_array(field, "VoxelProbes.shade: field");
            if (a.ndim() != 2 || a.shape(0) != py::ssize_t(p.voxels.size()) || a.shape(1) != 3)
                throw py::value_error("VoxelProbes.shade: field must be [" + std::to_string(p.voxels.size()) +
                                      ", 3] (one RGB value per surface voxel)");
            std::vector<float> values(a.data(), a.data() + a.size());
            const glm::vec3 at = vec3(position, "VoxelProbes.shade: position");
            ngi::ShadeStats st;
            ngi::Image img = [&] {
                py::gil_scoped_release release;
                return p.gi.shade(frame, at, ngi::Face::Front, values, ngi::VoxelFieldKind::Lighting, &st);
            }();
            return py::make_tuple(from_image(std::move(img)), st.no_voxel);
        }, py::arg("frame"), py::arg("position"), py::arg("field"),
           "(lighting [3, N, N], surface pixels without a voxel) of the frame's front view taken from `position` "
           "(its camera.json position), each pixel lit by the field's value at the voxel behind it.");
}

}  // namespace ngi_py
