// ngi render: one frame folder of a scene (features of the six faces + the front view's reference lighting).
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "ngi/camera_path.hpp"
#include "ngi/dataset.hpp"
#include "ngi/error.hpp"
#include "ngi/files.hpp"
#include "ngi/image_io.hpp"
#include "ngi/output_folder.hpp"
#include "ngi/render.hpp"
#include "ngi/scene.hpp"

namespace ngi_cli {

namespace {

struct Options {
    std::string spec, out, device, preview, area_light, camera_path = "auto";
    ngi::RenderSettings rs;
    bool no_reference = false;
    int frames = 100, frame = 0;
    int seed = -1;       // -1: the dataset's seed of the frame
    int path_seed = -1;  // -1: the dataset's path of the scene (seeded by its name)
    double time = -1.0;  // -1: not given, the scene's default time
};

// --area-light "cx,cy,cz,ux,uy,uz,vx,vy,vz,r,g,b": centre, half edges and radiance (ngi/area_light.hpp).
ngi::AreaLight parse_area_light(const std::string& text) {
    std::vector<float> v;
    std::size_t pos = 0;
    while (pos <= text.size()) {
        const std::size_t end = std::min(text.find(',', pos), text.size());
        const std::string item = text.substr(pos, end - pos);
        char* stop = nullptr;
        const double d = std::strtod(item.c_str(), &stop);
        if (item.empty() || stop != item.c_str() + item.size() || !std::isfinite(d) || std::abs(d) > 1.0e30)
            throw UsageError("--area-light needs 12 comma-separated numbers cx,cy,cz,ux,uy,uz,vx,vy,vz,r,g,b; '" +
                             item + "' is not a finite number");
        v.push_back(float(d));
        pos = end + 1;
    }
    if (v.size() != 12)
        throw UsageError("--area-light needs 12 comma-separated numbers cx,cy,cz,ux,uy,uz,vx,vy,vz,r,g,b, got " +
                         std::to_string(v.size()));
    ngi::AreaLight l;
    l.centre = {v[0], v[1], v[2]};
    l.half_u = {v[3], v[4], v[5]};
    l.half_v = {v[6], v[7], v[8]};
    l.radiance = {v[9], v[10], v[11]};
    ngi::check_area_light(l, "--area-light");
    return l;
}

// render.json, written into the frame folder with it: what the render was (scene, camera, settings) and what it
// took, for scripts (training's sequence and report tools) that would otherwise parse this command's output.
nlohmann::json render_record(const Options& o, const ngi::VoxelScene& scene, const ngi::CameraPose& pose, float hours,
                             const ngi::RenderSettings& rs, const ngi::RenderStats& st) {
    auto vec = [](glm::vec3 v) { return nlohmann::json::array({v.x, v.y, v.z}); };
    nlohmann::json r = {
        {"scene", {{"spec", o.spec}, {"name", scene.name}, {"size", {scene.size.x, scene.size.y, scene.size.z}}}},
        {"camera", {{"frame", o.frame}, {"path_frames", o.frames}, {"position", vec(pose.position)},
                    {"look", vec(pose.look)}, {"time_h", hours}}},
        {"path_seed", o.path_seed < 0 ? nlohmann::json(nullptr) : nlohmann::json(o.path_seed)},
        {"settings", {{"face", rs.n}, {"feature_spp", rs.feature_spp}, {"seed", rs.seed}}},
        {"timing", {{"features_ms", st.feature_ms}, {"feature_rays", st.feature_rays}}}};
    if (rs.reference) {
        r["settings"]["reference_spp"] = rs.reference_spp;
        r["settings"]["bounces"] = rs.max_bounces;
        r["timing"]["reference_ms"] = st.reference_ms;
        r["timing"]["reference_rays"] = st.reference_rays;
        r["timing"]["reference_rel_stderr"] = st.reference_rel_stderr;
    }
    return r;
}

int run(const Options& o) {
    const std::string &spec = o.spec, &out = o.out, &preview = o.preview;
    // Every option is checked before the (possibly long) render, most of them by the options themselves.
    ngi::RenderSettings rs = o.rs;
    rs.reference = !o.no_reference;
    const int frames = o.frames, frame = o.frame;
    if (frame > frames - 1)
        throw UsageError("--frame needs an integer in 0.." + std::to_string(frames - 1) + " (--path-frames " +
                         std::to_string(frames) + "), got '" + std::to_string(frame) + "'");
    if (std::error_code ec; !preview.empty() && std::filesystem::exists(preview, ec) &&
                            !std::filesystem::is_regular_file(preview, ec))  // found before the render, not after
        throw ngi::InputError("write " + preview + ": exists and is not a regular file; refusing to replace it");
    const double time = o.time;
    const ngi::AreaLight area_light = o.area_light.empty() ? ngi::AreaLight{} : parse_area_light(o.area_light);
    ngi::check_frame_folder_target(out);  // before the render, not after
    ngi::Device device = ngi::Device::open(o.device);
    const ngi::VoxelScene scene = ngi::make_scene(spec);
    const float hours = time < 0.0 ? scene.default_time : float(time);
    // The same path and seed as frame `frame` of this scene in a dataset with `frames` frames per scene, or (with
    // --path-seed) another path of the same kind: views of the scene that no dataset frame shares (ngi_train's
    // adapt renders its training frames on such paths and is judged on the dataset path).
    const ngi::CameraPathKind kind = ngi::parse_camera_path_kind(o.camera_path, "--camera-path");
    const ngi::CameraPath path = o.path_seed < 0
                                     ? ngi::dataset_camera_path(scene, frames, 25, kind)
                                     : ngi::make_camera_path(scene, kind, frames, std::uint32_t(o.path_seed), 25);
    const ngi::CameraPose pose = path.at(float(frame));
    rs.seed = o.seed >= 0 ? std::uint32_t(o.seed) : ngi::dataset_frame_seed(scene.name, frame);

    ngi::Renderer renderer(device, scene);
    ngi::RenderStats st;
    ngi::Lighting lighting = ngi::lighting_at(hours, scene.sun_azimuth);
    lighting.area_light = area_light;
    const ngi::Frame fr = renderer.render(pose, lighting, rs, &st);
    // Both outputs or neither: the preview goes to a temporary name first and is renamed after the frame
    // folder is in place (write_frame itself is all-or-nothing).
    std::string preview_tmp;
    if (!preview.empty()) {  // final front image: reference x albedo + emission + env (linear, clamped, sRGB)
        ngi::Image img(rs.n, rs.n, 3);
        const ngi::Face f = ngi::Face::Front;
        for (std::size_t i = 0; i < img.data.size(); ++i) {
            const float light = fr.reference ? fr.reference->data[i] : fr.get(ngi::Feature::Direct, f).data[i];
            img.data[i] = light * fr.get(ngi::Feature::Albedo, f).data[i] + fr.get(ngi::Feature::Emission, f).data[i] +
                          fr.get(ngi::Feature::Env, f).data[i];
        }
        preview_tmp = ngi::staging_name(preview);  // within NAME_MAX however long the name is
        ngi::write_png(preview_tmp, img, ngi::PngEncoding::Srgb);
    }
    try {
        const std::unique_ptr<ngi::OutputFolder> folder = ngi::frame_output_folder(out);
        ngi::write_frame_files(*folder, fr);
        folder->write_text("render.json", render_record(o, scene, pose, hours, rs, st).dump(2) + "\n");
        folder->commit();
        if (!preview.empty()) {
            std::error_code ec;
            std::filesystem::rename(preview_tmp, preview, ec);
            if (ec) throw ngi::InputError("ngi render: cannot move the preview into place as " + preview + ": " +
                                          ec.message() + " (the frame folder " + out + " was written)");
        }
    } catch (...) {
        if (!preview_tmp.empty()) {
            std::error_code ec;
            std::filesystem::remove(preview_tmp, ec);
        }
        throw;
    }
    const double rays = double(st.feature_rays + st.reference_rays), ms = st.feature_ms + st.reference_ms;
    std::printf("scene      %s (%d x %d x %d blocks, %zu materials)\n", scene.name.c_str(), scene.size.x, scene.size.y,
                scene.size.z, scene.palette.size() - 1);
    std::printf("camera     frame %d/%d at (%.2f, %.2f, %.2f), look (%.2f, %.2f, %.2f), time %.2f h\n", frame, frames,
                pose.position.x, pose.position.y, pose.position.z, pose.look.x, pose.look.y, pose.look.z, hours);
    std::printf("features   6 x %d^2, %d spp direct: %.1f ms, %.2f Mrays\n", rs.n, rs.feature_spp, st.feature_ms,
                st.feature_rays * 1e-6);
    if (rs.reference)
        std::printf("reference  %d spp, %d bounces: %.1f ms, %.2f Mrays, relative std error %.3f\n", rs.reference_spp,
                    rs.max_bounces, st.reference_ms, st.reference_rays * 1e-6, st.reference_rel_stderr);
    std::printf("total      %.1f ms, %.2f Mrays/s -> %s\n", ms, rays / (ms * 1e3), out.c_str());
    return 0;
}

}  // namespace

Run add_render(CLI::App& app) {
    auto o = std::make_shared<Options>();
    ngi::RenderSettings& rs = o->rs;
    CLI::App* cmd = add_command(app, "render", "path-trace one frame folder of a scene",
                                "The features of the six faces and the front view's reference lighting; the camera "
                                "and the seed of frame K of the scene in a dataset.");
    add_path(*cmd, "--scene", o->spec, "SPEC",
             "room|street|cave|backlit|bleed|sculpture|cornell|knot|superquadric|blob[:seed=S,...], or a .vox or "
             "mesh file (.obj, .ply, .gltf, .glb)", true);
    add_path(*cmd, "--out", o->out, "DIR", "the frame folder to write (render.json in it: scene, camera, timings)",
             true);
    // The limits are those of a dataset config.
    add_integer(*cmd, "--frame", o->frame, 0, ngi::kMaxPathFrames - 1, "K", "the frame of the camera path, below --path-frames");
    add_integer(*cmd, "--face", rs.n, 1, 8192, "N", "face size in pixels");
    add_integer(*cmd, "--spp", rs.reference_spp, 1, 1 << 20, "S", "samples per pixel of the reference");
    add_real(*cmd, "--time", o->time, 0.0, 48.0, "HOURS", "time of day", "the scene's");
    add_device(*cmd, o->device);
    add_integer(*cmd, "--feature-spp", rs.feature_spp, 1, 1 << 20, "F", "samples per pixel of the direct feature");
    add_integer(*cmd, "--bounces", rs.max_bounces, 0, 1000, "B", "indirect bounces of the reference");
    add_integer(*cmd, "--path-frames", o->frames, 1, ngi::kMaxPathFrames, "P", "frames of the scene's camera path");
    add_choice(*cmd, "--camera-path", o->camera_path, {"auto", "fly", "orbit"},
               "the camera path: fly = through the scene's free space, orbit = around its solid blocks looking at "
               "them, auto = orbit for a .vox file, fly for a procedural scene (as a dataset's \"camera_path\")",
               "auto");
    add_integer(*cmd, "--seed", o->seed, 0, 2147483647, "S",
                "random seed of the path tracer (a second, independent render of the same frame measures the "
                "reference's noise)", "the dataset's seed of frame K");
    add_integer(*cmd, "--path-seed", o->path_seed, 0, 2147483647, "S",
                "seed of the camera path (another path of the same kind through or around the same scene)",
                "the dataset's path of the scene");
    add_switch(*cmd, "--no-reference", o->no_reference, "render the features only");
    add_nonempty(*cmd, "--preview", o->preview, "PNG",
                 "also write the front view's final image (reference x albedo + emission + env) as an sRGB PNG");
    add_nonempty(*cmd, "--area-light", o->area_light, "C,U,V,L",
                 "a rectangular area light (not a block; lit by next-event estimation): 12 numbers "
                 "cx,cy,cz,ux,uy,uz,vx,vy,vz,r,g,b = centre, orthogonal half-edge vectors (it emits toward "
                 "cross(u, v)) and radiance; recorded in camera.json");
    return [o] { return run(*o); };
}

}  // namespace ngi_cli
