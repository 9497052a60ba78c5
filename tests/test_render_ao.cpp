// The path tracer's ambient-occlusion estimator (Renderer::render_ao, kernels/render_ao.cl pt_ao) against exact
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

namespace {

// Naive reference of pt_geometry's smooth normal at surface point p (face normal nf): minus the gradient of the
// Gaussian-blurred occupancy, in double precision, every solid block within ceil(2 sigma) + 1 of p.
glm::vec3 smooth_normal_reference(const VoxelScene& s, glm::vec3 p, glm::vec3 nf, float sigma) {
    const int r = int(std::ceil(2.0f * sigma)) + 1;
    const glm::ivec3 c0 = glm::ivec3(glm::floor(p));
    glm::dvec3 g(0.0);
    for (int z = c0.z - r; z <= c0.z + r; ++z)
        for (int y = c0.y - r; y <= c0.y + r; ++y)
            for (int x = c0.x - r; x <= c0.x + r; ++x) {
                if (x < 0 || y < 0 || z < 0 || x >= s.size.x || y >= s.size.y || z >= s.size.z) continue;
                if (s.at({x, y, z}) == 0) continue;
                const glm::dvec3 v = glm::dvec3(p) - (glm::dvec3(x, y, z) + 0.5);
                const double d2 = glm::dot(v, v);
                if (d2 > double(r * r)) continue;
                g += v * std::exp(-d2 / (2.0 * sigma * sigma));
            }
    const double len = glm::length(g);
    return len > 1e-12 && glm::dot(g, glm::dvec3(nf)) > 0 ? glm::vec3(g / len) : nf;
}

}  // namespace

TEST_CASE("geometry: face normals, planar depth and smooth normals match a naive reference, a ball's smooth "
          "normals are radial", "[render][ao]") {
    Device& dev = test::device();
    // A ball of radius 9 blocks around (16, 16, 16) in a 33^3 grid (odd, not a power of two).
    VoxelScene s({33, 33, 33}, "ball");
    const auto m = s.add_material({glm::vec3(0.5f), glm::vec3(0.0f), false});
    const glm::vec3 centre(16.5f);
    for (int z = 0; z < 33; ++z)
        for (int y = 0; y < 33; ++y)
            for (int x = 0; x < 33; ++x)
                if (glm::length(glm::vec3(x, y, z) + 0.5f - centre) <= 9.0f) s.fill({x, y, z}, {x + 1, y + 1, z + 1}, m);
    Renderer r(dev, s);
    RenderSettings rs;
    rs.n = 37;
    CameraPose pose;
    pose.position = centre + glm::vec3(3.0f, 5.0f, 14.0f);
    pose.look = glm::normalize(centre - pose.position);
    pose.up = glm::vec3(0, 1, 0);
    const FaceBasis b = CameraCluster::from_look_up(pose.look, pose.up).face(Face::Front);
    const float sigma = 1.5f;
    const Image g = r.render_geometry(pose, rs, sigma);
    REQUIRE(g.channels == 7);
    REQUIRE(r.render_geometry(pose, rs, sigma).data == g.data);
    int surface = 0, sky = 0;
    double face_err = 0, smooth_err = 0;
    for (int y = 0; y < rs.n; ++y)
        for (int x = 0; x < rs.n; ++x) {
            const glm::vec3 nf(g.at(3, y, x), g.at(4, y, x), g.at(5, y, x));
            const float depth = g.at(6, y, x);
            if (nf == glm::vec3(0.0f)) {
                REQUIRE(depth == 1.0e4f);
                REQUIRE(glm::vec3(g.at(0, y, x), g.at(1, y, x), g.at(2, y, x)) == glm::vec3(0.0f));
                ++sky;
                continue;
            }
            ++surface;
            REQUIRE(std::abs(glm::length(nf) - 1.0f) < 1e-6f);
            const glm::vec3 d = face_pixel_direction(b, x, y, rs.n);
            const glm::vec3 p = pose.position + d * (depth / glm::dot(d, b.look));
            // The hit lies on a block face whose outward normal is nf: p's coordinate along nf is an integer.
            const int axis = nf.x != 0 ? 0 : (nf.y != 0 ? 1 : 2);
            REQUIRE(std::abs(p[axis] - std::round(p[axis])) < 1e-3f);
            const glm::vec3 ns(g.at(0, y, x), g.at(1, y, x), g.at(2, y, x));
            const glm::vec3 ref = smooth_normal_reference(s, p, nf, sigma);
            INFO("pixel " << x << "," << y);
            REQUIRE(glm::length(ns - ref) < 2e-3f);  // p reconstructed from float depth: ~1e-5 m off
            const glm::vec3 radial = glm::normalize(p - centre);
            face_err += std::acos(std::min(1.0f, glm::dot(nf, radial)));
            smooth_err += std::acos(std::min(1.0f, glm::dot(ns, radial)));
        }
    REQUIRE(surface > 200);
    REQUIRE(sky > 100);
    face_err /= surface;
    smooth_err /= surface;
    INFO("mean angle to the ball's radial direction: face " << face_err << " rad, smooth " << smooth_err << " rad");
    // Face normals of a voxel sphere are off by up to 55 degrees (about 0.4 rad on average); the blurred
    // occupancy's gradient follows the sphere.
    REQUIRE(face_err > 0.25);
    REQUIRE(smooth_err < 0.12);
    REQUIRE(r.render_geometry(pose, rs, 0.0f).data != g.data);
    const Image flat = r.render_geometry(pose, rs, 0.0f);
    for (int i = 0; i < 3 * rs.n * rs.n; ++i) REQUIRE(flat.data[i] == flat.data[i + 3 * rs.n * rs.n]);
    REQUIRE_THROWS_WITH(r.render_geometry(pose, rs, -1.0f), Catch::Contains("smoothing sigma"));
    REQUIRE_THROWS_WITH(r.render_geometry(pose, rs, NAN), Catch::Contains("smoothing sigma"));
}
