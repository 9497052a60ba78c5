// The renderer follows camera.hpp's cluster conventions exactly, and camera paths behave.
#include <catch2/catch.hpp>
#include <cmath>

#include "ngi/camera.hpp"
#include "ngi/camera_path.hpp"
#include "ngi/render.hpp"
#include "ngi/scene.hpp"
#include "test_support.hpp"

using namespace ngi;

// [oclgrind-small]: render test cases cheap enough to run under oclgrind (~10-15 s each there; the whole [render]
// set takes far longer): `oclgrind --data-races --check-api --log LOG tests/ngi_tests "[oclgrind-small]"` with
// NGI_TEST_DEVICE=0:0 (oclgrind's platform); oclgrind exits 0 even when it reports, so LOG must be empty.
// This case also guards the DDA against oclgrind 21.10's wrong vector select (kernels/scene.cl, trace_grid).
TEST_CASE("six faces: a ray through face pixel (col, row) of camera.hpp hits what the kernel reports",
          "[render][oclgrind-small]") {
    // A 9 m room whose six walls have distinct colours; interior [1, 8)^3.
    VoxelScene s({9, 9, 9}, "walls");
    const glm::vec3 colour[6] = {{0.9f, 0.1f, 0.1f}, {0.1f, 0.9f, 0.1f}, {0.1f, 0.1f, 0.9f},
                                 {0.9f, 0.9f, 0.1f}, {0.1f, 0.9f, 0.9f}, {0.9f, 0.1f, 0.9f}};  // +x -x +y -y +z -z
    std::uint8_t m[6];
    for (int i = 0; i < 6; ++i) m[i] = s.add_material({colour[i], glm::vec3(0.0f), false});
    s.fill({8, 0, 0}, {9, 9, 9}, m[0]);
    s.fill({0, 0, 0}, {1, 9, 9}, m[1]);
    s.fill({1, 8, 0}, {8, 9, 9}, m[2]);
    s.fill({1, 0, 0}, {8, 1, 9}, m[3]);
    s.fill({1, 1, 8}, {8, 8, 9}, m[4]);
    s.fill({1, 1, 0}, {8, 8, 1}, m[5]);

    Renderer r(test::device(), s);
    RenderSettings rs;
    rs.feature_spp = 8;  // noise is fine here: these checks are not about light quality
    rs.n = 20;
    rs.reference = false;
    const CameraPose pose{{3.7f, 4.2f, 5.1f}, glm::normalize(glm::vec3(1.0f, 0.3f, -0.5f)), {0.1f, 1.0f, 0.0f}};
    const Frame fr = r.render(pose, Lighting{}, rs);
    CHECK(fr.look == pose.look);
    CHECK(fr.up == pose.up);

    const CameraCluster cl = CameraCluster::from_look_up(pose.look, pose.up);
    int checked = 0;
    for (int f = 0; f < kFaceCount; ++f) {
        const FaceBasis b = cl.face(Face(f));
        for (int row = 0; row < rs.n; ++row)
            for (int col = 0; col < rs.n; ++col) {
                const glm::vec3 d = glm::normalize(face_pixel_direction(b, col, row, rs.n));
                // Distance to each interior wall plane; the nearest one is hit.
                float t[6];
                for (int k = 0; k < 3; ++k) {
                    t[2 * k] = d[k] > 0 ? (8.0f - pose.position[k]) / d[k] : 1e30f;      // +axis wall at 8
                    t[2 * k + 1] = d[k] < 0 ? (1.0f - pose.position[k]) / d[k] : 1e30f;  // -axis wall at 1
                }
                int w = 0;
                for (int k = 1; k < 6; ++k) if (t[k] < t[w]) w = k;
                float second = 1e30f;
                for (int k = 0; k < 6; ++k) if (k != w) second = std::min(second, t[k]);
                if (second - t[w] < 0.05f) continue;  // near a corner of the room
                for (int c = 0; c < 3; ++c)
                    REQUIRE(fr.get(Feature::Albedo, Face(f)).at(c, row, col) == colour[w][c]);
                const glm::vec3 inward = -glm::vec3(w / 2 == 0, w / 2 == 1, w / 2 == 2) * (w % 2 == 0 ? 1.0f : -1.0f);
                for (int c = 0; c < 3; ++c) REQUIRE(fr.get(Feature::Normal, Face(f)).at(c, row, col) == inward[c]);
                // Depth: planar, along the face's look axis.
                REQUIRE(fr.get(Feature::Depth, Face(f)).at(0, row, col) ==
                        Approx(t[w] * glm::dot(d, b.look)).epsilon(1e-4));
                ++checked;
            }
    }
    CHECK(checked > 6 * 20 * 20 * 3 / 4);
}

TEST_CASE("camera paths: keyframes every 25 frames, smooth, clear of blocks, deterministic", "[render]") {
    for (const char* spec : {"room:seed=4", "cave:seed=2", "backlit:seed=3", "street:seed=1", "bleed:seed=8"}) {
        const VoxelScene s = make_scene(spec);
        const CameraPath p = make_camera_path(s, 101, 9);
        INFO(spec);
        CHECK(p.interval == 25);
        CHECK(p.frame_count() >= 101);
        CHECK(p.keys.size() == 5);
        for (std::size_t k = 0; k < p.keys.size(); ++k) {  // the spline passes through its keyframes
            const CameraPose at = p.at(float(k * 25));
            CHECK(glm::length(at.position - p.keys[k].position) < 1e-4f);
            CHECK(clear_of_blocks(s, p.keys[k].position, 0.5f));
        }
        glm::vec3 prev = p.at(0).position;
        for (int f = 0; f < p.frame_count(); ++f) {
            const CameraPose c = p.at(float(f));
            REQUIRE(clear_of_blocks(s, c.position, 0.3f));
            REQUIRE(std::abs(glm::length(c.look) - 1.0f) < 1e-4f);
            REQUIRE(std::abs(glm::dot(c.look, c.up)) < 1e-4f);
            REQUIRE(c.up.y > 0.9f);                           // no roll, modest pitch
            REQUIRE(glm::length(c.position - prev) < 1.0f);  // no jumps between frames
            prev = c.position;
        }
        const CameraPath again = make_camera_path(s, 101, 9);
        for (std::size_t k = 0; k < p.keys.size(); ++k) CHECK(again.keys[k].position == p.keys[k].position);
        if (s.camera.look)  // backlit: the camera looks away from the opening
            for (const auto& k : p.keys) CHECK(glm::dot(k.orientation * glm::vec3(0, 0, -1), *s.camera.look) > 0.7f);
    }
    // Orientation: slerp between consecutive keyframes.
    CameraPath p;
    p.keys = {{{0, 0, 0}, glm::quatLookAtRH(glm::vec3(0, 0, -1), glm::vec3(0, 1, 0))},
              {{1, 0, 0}, glm::quatLookAtRH(glm::vec3(1, 0, 0), glm::vec3(0, 1, 0))}};
    const CameraPose mid = p.at(12.5f);
    CHECK(mid.look.x == Approx(std::sqrt(0.5f)).epsilon(1e-4));
    CHECK(mid.look.z == Approx(-std::sqrt(0.5f)).epsilon(1e-4));
    CHECK(mid.position.x == Approx(0.5f).epsilon(1e-5));
}
