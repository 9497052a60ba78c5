// An out-of-tree consumer of ngi::render: a procedural room, one 16 x 16 frame's features from the middle of its
// camera region; checks the depth is finite and positive where the camera sees a surface.
#include <cmath>
#include <cstdio>
#include <exception>
#include <ngi/render.hpp>
#include <ngi/scene.hpp>
#include <stdexcept>
#include <string>

int main() {
    try {
        ngi::Device device = ngi::Device::open();
        const ngi::VoxelScene scene = ngi::make_scene("room:seed=1");
        ngi::Renderer renderer(device, scene);
        ngi::CameraPose pose;
        pose.position = 0.5f * (scene.camera.region_lo + scene.camera.region_hi);
        ngi::RenderSettings settings;
        settings.n = 16;
        settings.feature_spp = 1;
        settings.reference = false;
        const ngi::Frame frame = renderer.render(pose, ngi::lighting_at(scene.default_time, scene.sun_azimuth), settings);
        const ngi::Image& depth = frame.get(ngi::Feature::Depth, ngi::Face::Front);
        int seen = 0;
        for (float d : depth.data) {
            if (!std::isfinite(d) || d < 0.0f) throw std::runtime_error("depth " + std::to_string(d));
            seen += d > 0.0f;
        }
        if (frame.n != 16 || seen == 0) throw std::runtime_error("the front face sees nothing");
        std::fprintf(stderr, "c++ render consumer: %s, a 16x16 frame, %d of %zu front pixels see a surface\n",
                     scene.name.c_str(), seen, depth.data.size());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "c++ render consumer: %s\n", e.what());
        return 1;
    }
    return 0;
}
