// ngi voxel-data: seed 004's per-voxel data of one scene (docs/VOXEL_FIELD.md): the surface voxels' attributes and
// the path-traced SH-27 of the light each receives, plus the lighting at its probe point and at its exposed faces
// (validation targets). One folder of .npy files + scene.json; all or nothing (OutputFolder).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "ngi/error.hpp"
#include "ngi/output_folder.hpp"
#include "ngi/render.hpp"
#include "ngi/scene.hpp"
#include "ngi/tensor.hpp"
#include "ngi/voxel_field.hpp"

namespace ngi_cli {
namespace {

const std::vector<std::string> kFiles = {"attributes.npy", "sh.npy",       "normal.npy",        "probe.npy",
                                         "exposed.npy",    "direct.npy",   "lighting.npy",      "face_lighting.npy",
                                         "sh_second.npy",  "scene.json"};

ngi::Tensor tensor(std::vector<int> shape, const std::vector<float>& data) {
    ngi::Tensor t(std::move(shape));
    if (t.data.size() != data.size())
        throw ngi::Error("voxel-data: internal size mismatch for " + ngi::shape_string(t.shape));
    t.data = data;
    return t;
}

std::vector<float> flatten(const std::vector<glm::vec3>& v) {
    std::vector<float> out;
    out.reserve(v.size() * 3);
    for (const glm::vec3& x : v) out.insert(out.end(), {x.x, x.y, x.z});
    return out;
}

// Relative RMS difference of two estimates of the same coefficients (the projection's noise, over all voxels).
double relative_rms(const std::vector<float>& a, const std::vector<float>& b) {
    double d = 0, s = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        d += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
        s += 0.5 * (double(a[i]) * a[i] + double(b[i]) * b[i]);
    }
    return s > 0 ? std::sqrt(d / s) : 0.0;
}

struct Options {
    std::string spec, out, device;
    double time = -1.0;
    ngi::VoxelFieldSettings vs;
    bool noise = false;
    int seed = 0;  // bound to --seed (an int option), copied into vs.seed
};

int run(Options o) {
    o.vs.seed = std::uint32_t(o.seed);
    ngi::OutputFolder out(o.out, "write", kFiles);
    ngi::Device device = ngi::Device::open(o.device);
    const ngi::VoxelScene scene = ngi::make_scene(o.spec);
    const float hours = o.time < 0.0 ? scene.default_time : float(o.time);
    const ngi::Lighting lighting = ngi::lighting_at(hours, scene.sun_azimuth);
    const auto t0 = std::chrono::steady_clock::now();
    const ngi::SurfaceVoxels voxels = ngi::surface_voxels(device, scene, lighting);
    const int V = int(voxels.size());
    std::printf("scene      %s (%d x %d x %d blocks), time %.2f h: %d surface voxels\n", scene.name.c_str(),
                scene.size.x, scene.size.y, scene.size.z, double(hours), V);
    std::fflush(stdout);
    ngi::Renderer renderer(device, scene);
    const ngi::VoxelField f = renderer.render_voxel_field(voxels, lighting, o.vs);
    std::printf("field      %d directions, %d point samples, %d bounces: %.1f s, %.1f Mrays\n", o.vs.directions,
                o.vs.point_samples, o.vs.max_bounces, f.ms * 1e-3, double(f.rays) * 1e-6);
    nlohmann::json noise = nullptr;
    if (o.noise) {  // a second, independent estimate: the projection's noise, measured
        ngi::VoxelFieldSettings second = o.vs;
        second.seed = o.vs.seed ^ 0x9e3779b9u;
        const ngi::VoxelField g = renderer.render_voxel_field(voxels, lighting, second);
        const double sh = relative_rms(f.sh, g.sh), lit = relative_rms(f.lighting, g.lighting),
                     faces = relative_rms(f.face_lighting, g.face_lighting);
        // The mean of two independent estimates has half the variance: the noise of one is rms(a - b) / sqrt(2).
        noise = {{"sh_relative_rms", sh / std::sqrt(2.0)},
                 {"lighting_relative_rms", lit / std::sqrt(2.0)},
                 {"face_lighting_relative_rms", faces / std::sqrt(2.0)},
                 {"note", "relative RMS difference of two independent estimates (seeds differ) / sqrt(2): the "
                          "noise of one estimate"}};
        std::printf("noise      relative RMS of one estimate: SH %.4f, probe lighting %.4f, face lighting %.4f\n",
                    sh / std::sqrt(2.0), lit / std::sqrt(2.0), faces / std::sqrt(2.0));
        out.write("sh_second.npy", [&](const std::string& p) { ngi::write_npy(p, tensor({V, 27}, g.sh)); });
    }
    std::vector<float> exposed(voxels.exposed.begin(), voxels.exposed.end());
    out.write("attributes.npy", [&](const std::string& p) {
        ngi::write_npy(p, tensor({V, ngi::kVoxelAttributes}, voxels.attributes));
    });
    out.write("sh.npy", [&](const std::string& p) { ngi::write_npy(p, tensor({V, 27}, f.sh)); });
    out.write("normal.npy", [&](const std::string& p) { ngi::write_npy(p, tensor({V, 3}, flatten(voxels.normal))); });
    out.write("probe.npy", [&](const std::string& p) { ngi::write_npy(p, tensor({V, 3}, flatten(voxels.probe))); });
    out.write("exposed.npy", [&](const std::string& p) { ngi::write_npy(p, tensor({V}, exposed)); });
    out.write("direct.npy", [&](const std::string& p) { ngi::write_npy(p, tensor({V, 3}, f.direct)); });
    out.write("lighting.npy", [&](const std::string& p) { ngi::write_npy(p, tensor({V, 3}, f.lighting)); });
    out.write("face_lighting.npy",
              [&](const std::string& p) { ngi::write_npy(p, tensor({V, 6, 3}, f.face_lighting)); });
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const nlohmann::json meta = {
        {"name", scene.name},
        {"grid", {scene.size.x, scene.size.y, scene.size.z}},
        {"voxels", V},
        {"time_hours", hours},
        {"sun_azimuth", scene.sun_azimuth},
        {"directions", o.vs.directions},
        {"sun_rays", o.vs.sun_rays},
        {"point_samples", o.vs.point_samples},
        {"max_bounces", o.vs.max_bounces},
        {"seed", o.vs.seed},
        {"field_ms", f.ms},
        {"rays", f.rays},
        {"seconds", seconds},
        {"device", device.info().name},
        {"noise", noise},
        {"conventions", "docs/VOXEL_FIELD.md; attributes: centre xyz (m), albedo rgb, emission rgb, voxel id; "
                        "sh [V][3][9] (CONVENTIONS section 14); lighting = irradiance / pi"}};
    out.write_text("scene.json", meta.dump(2) + "\n");
    out.commit();
    std::printf("written    %s (%.1f s)\n", o.out.c_str(), seconds);
    return 0;
}

}  // namespace

Run add_voxel_data(CLI::App& app) {
    auto o = std::make_shared<Options>();
    CLI::App* cmd = add_command(
        app, "voxel-data", "seed 004's per-voxel attributes and path-traced SH-27 ground truth of a scene",
        "Writes attributes.npy [V,10], sh.npy [V,27], normal.npy, probe.npy, exposed.npy, direct.npy, lighting.npy, "
        "face_lighting.npy [V,6,3] and scene.json (docs/VOXEL_FIELD.md); with --noise also sh_second.npy, a second "
        "independent estimate, and the measured noise in scene.json.");
    add_path(*cmd, "--scene", o->spec, "SPEC", "a procedural family[:seed=S] (e.g. cornell:seed=3) or a .vox file",
             true);
    add_path(*cmd, "--out", o->out, "DIR", "the folder to write", true);
    add_real(*cmd, "--time", o->time, 0.0, 48.0, "HOURS", "time of day", "the scene's");
    add_integer(*cmd, "--directions", o->vs.directions, 1, 1 << 16, "M",
                "stratified directions of the SH projection (a square number)");
    add_integer(*cmd, "--sun-rays", o->vs.sun_rays, 1, 1 << 16, "K", "shadow rays toward the sun per voxel");
    add_integer(*cmd, "--samples", o->vs.point_samples, 1, 1 << 20, "S",
                "lighting samples per probe point and per exposed face");
    add_integer(*cmd, "--bounces", o->vs.max_bounces, 0, 1000, "B", "indirect bounces");
    add_integer(*cmd, "--seed", o->seed, 0, 1 << 30, "SEED", "seed of the estimates");
    add_switch(*cmd, "--noise", o->noise, "also a second independent estimate: the noise, measured (twice the time)");
    add_device(*cmd, o->device);
    return [o] { return run(*o); };
}

}  // namespace ngi_cli
