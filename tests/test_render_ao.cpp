// The path tracer's ambient-occlusion estimator (Renderer::render_ao, kernels/pathtrace.cl pt_ao) against exact
// cases: a closed box (every ray hits: 0; no ray reaches with a short max distance: 1), and a point on a floor
// next to a tall wall (an infinite wall hides exactly half of the cosine-weighted hemisphere).
#include <glm/glm.hpp>

#include "ngi/camera.hpp"
#include "ngi/render.hpp"
#include "ngi/scene.hpp"
#include "test_support.hpp"

using namespace ngi;

TEST_CASE("ambient occlusion: closed box 0 and 1 exactly, half-space wall 1/2, deterministic", "[render][ao]") {
    Device& dev = test::device();
    RenderSettings rs;
    rs.n = 16;
    rs.seed = 7;
    {
        VoxelScene box({9, 9, 9}, "box");
        const auto m = box.add_material({glm::vec3(0.5f), glm::vec3(0.0f), false});
        box.fill({0, 0, 0}, {9, 9, 9}, m);
        box.fill({1, 1, 1}, {8, 8, 8}, 0);
        Renderer r(dev, box);
        CameraPose pose;
        pose.position = glm::vec3(4.5f);
        const Image enclosed = r.render_ao(pose, rs, 64, INFINITY);
        for (float v : enclosed.data) REQUIRE(v == 0.0f);
        // The front wall is 3.5 m away and the side walls 3.5 m from its centre: central pixels see wall points
        // farther than 0.5 m from any other block, so no ray of length 0.5 can hit anything.
        const Image open = r.render_ao(pose, rs, 64, 0.5f);
        for (int y = 4; y < 12; ++y)
            for (int x = 4; x < 12; ++x) REQUIRE(open.at(0, y, x) == 1.0f);
        REQUIRE(r.render_ao(pose, rs, 64, 0.5f).data == open.data);  // same seed, same bits
        REQUIRE_THROWS_WITH(r.render_ao(pose, rs, 0, 1.0f), Catch::Contains("rays per pixel"));
        REQUIRE_THROWS_WITH(r.render_ao(pose, rs, 8, -1.0f), Catch::Contains("max distance"));
    }
    {
        // Floor (y = 0) and a wall filling x in [40, 41) over the whole height and depth of the grid.
        VoxelScene s({48, 64, 64}, "wall");
        const auto m = s.add_material({glm::vec3(0.5f), glm::vec3(0.0f), false});
        s.fill({0, 0, 0}, {48, 1, 64}, m);
        s.fill({40, 0, 0}, {41, 64, 64}, m);
        Renderer r(dev, s);
        CameraPose pose;
        pose.position = glm::vec3(38.5f, 3.0f, 32.0f);
        pose.look = glm::vec3(0, -1, 0);  // straight down at the floor
        pose.up = glm::vec3(0, 0, -1);
        const int rays = 4096;
        const Image ao = r.render_ao(pose, rs, rays, INFINITY);
        const FaceBasis b = CameraCluster::from_look_up(pose.look, pose.up).face(Face::Front);
        int checked = 0;
        for (int y = 0; y < rs.n; ++y)
            for (int x = 0; x < rs.n; ++x) {
                const glm::vec3 d = face_pixel_direction(b, x, y, rs.n);
                const glm::vec3 p = pose.position + d * ((1.0f - pose.position.y) / d.y);  // the floor's top, y = 1
                const float to_wall = 40.0f - p.x;
                if (to_wall < 0.3f || to_wall > 3.0f || std::abs(p.z - 32.0f) > 3.0f) continue;
                // Exactly 1/2 for an infinite wall; the 63 m high, 64 m deep wall lets a little more through
                // (over the top: < 0.003 at 3 m; past its ends: < 0.05), and 4096 rays have a standard error of
                // 0.008: [0.47, 0.58].
                CAPTURE(x, y, to_wall);
                REQUIRE(ao.at(0, y, x) >= 0.47f);
                REQUIRE(ao.at(0, y, x) <= 0.58f);
                if (checked == 0) WARN("AO at " << to_wall << " m from the wall: " << ao.at(0, y, x));
                ++checked;
            }
        REQUIRE(checked >= 8);
    }
}
