// ngi render: one frame folder of a scene (features of the six faces + the front view's reference lighting).
#include <cstdio>
#include <string>

#include "commands.hpp"
#include "ngi/camera_path.hpp"
#include "ngi/dataset.hpp"
#include "ngi/image_io.hpp"
#include "ngi/render.hpp"
#include "ngi/scene.hpp"

namespace ngi_cli {
namespace {

int int_option(const Args& a, const std::string& name, int fallback) {
    if (!a.has(name)) return fallback;
    try {
        std::size_t used = 0;
        const int v = std::stoi(a.get(name), &used);
        if (used == a.get(name).size()) return v;
    } catch (const std::exception&) {
    }
    throw UsageError("--" + name + " needs an integer, got '" + a.get(name) + "'");
}

}  // namespace

int cmd_render(int argc, char** argv) {
    Args args(argc, argv, 2, {"no-reference"});
    const std::string spec = args.require("scene"), out = args.require("out");
    ngi::Device device = ngi::Device::open(args.get("device"));
    const ngi::VoxelScene scene = ngi::make_scene(spec);

    ngi::RenderSettings rs;
    rs.n = int_option(args, "face", rs.n);
    rs.reference_spp = int_option(args, "spp", rs.reference_spp);
    rs.feature_spp = int_option(args, "feature-spp", rs.feature_spp);
    rs.max_bounces = int_option(args, "bounces", rs.max_bounces);
    rs.reference = !args.has("no-reference");
    const int frame = int_option(args, "frame", 0);
    const int frames = int_option(args, "path-frames", 100);
    if (frame < 0 || frame >= frames) throw UsageError("--frame must be in 0.." + std::to_string(frames - 1));
    float hours = scene.default_time;
    if (args.has("time")) {
        try {
            hours = std::stof(args.get("time"));
        } catch (const std::exception&) {
            throw UsageError("--time needs hours (e.g. 13.5), got '" + args.get("time") + "'");
        }
    }
    // The same path and seed as frame `frame` of this scene in a dataset with `frames` frames per scene.
    const ngi::CameraPath path = ngi::dataset_camera_path(scene, frames, 25);
    const ngi::CameraPose pose = path.at(float(frame));
    rs.seed = ngi::dataset_frame_seed(scene.name, frame);

    ngi::Renderer renderer(device, scene);
    ngi::RenderStats st;
    const ngi::Frame fr = renderer.render(pose, ngi::lighting_at(hours, scene.sun_azimuth), rs, &st);
    ngi::write_frame(out, fr);
    if (args.has("preview")) {  // final front image: reference x albedo + emission + env (linear, clamped, sRGB)
        ngi::Image img(rs.n, rs.n, 3);
        const ngi::Face f = ngi::Face::Front;
        for (std::size_t i = 0; i < img.data.size(); ++i) {
            const float light = fr.reference ? fr.reference->data[i] : fr.get(ngi::Feature::Direct, f).data[i];
            img.data[i] = light * fr.get(ngi::Feature::Albedo, f).data[i] + fr.get(ngi::Feature::Emission, f).data[i] +
                          fr.get(ngi::Feature::Env, f).data[i];
        }
        ngi::write_png(args.get("preview"), img, ngi::PngEncoding::Srgb);
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

}  // namespace ngi_cli
