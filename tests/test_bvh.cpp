// The triangle BVH (render/bvh.cpp, kernels/bvh.cl) against brute-force intersection on random triangle soups,
// watertightness on a closed sphere, determinism and the depth bound.
#include <cstring>
#include <random>

#include <glm/glm.hpp>

#include "mesh_shapes.hpp"
#include "ngi/render.hpp"
#include "ngi/scene.hpp"
#include "render/bvh.hpp"
#include "test_support.hpp"

using namespace ngi;

namespace {

TriangleMesh random_soup(std::mt19937& rng, int count, float extent, float size) {
    std::uniform_real_distribution<float> pos(0.0f, extent), off(-size, size);
    TriangleMesh m;
    for (int i = 0; i < count; ++i) {
        const glm::vec3 c(pos(rng), pos(rng), pos(rng));
        const auto base = unsigned(m.positions.size());
        for (int k = 0; k < 3; ++k) {
            m.positions.push_back(c + glm::vec3(off(rng), off(rng), off(rng)));
            m.normals.push_back({0, 1, 0});
        }
        m.triangles.push_back({base, base + 1, base + 2});
        m.materials.push_back(1);
    }
    return m;
}

// 8 floats per ray: origin, tmax, direction, 0.
void add_ray(std::vector<float>& rays, glm::vec3 o, glm::vec3 d, float tmax) {
    rays.insert(rays.end(), {o.x, o.y, o.z, tmax, d.x, d.y, d.z, 0.0f});
}

glm::vec3 random_unit(std::mt19937& rng) {
    std::normal_distribution<float> g;
    for (;;) {
        const glm::vec3 v(g(rng), g(rng), g(rng));
        if (glm::length(v) > 1e-3f) return glm::normalize(v);
    }
}

}  // namespace

TEST_CASE("bvh: closest and any hits equal brute force on random triangle soups", "[bvh]") {
    std::mt19937 rng(20261128);
    for (const int count : {1, 2, 5, 17, 100, 1000, 3001}) {
        const TriangleMesh mesh = random_soup(rng, count, 10.0f, count > 100 ? 0.8f : 3.0f);
        const detail::Bvh bvh = detail::build_bvh(mesh);
        CAPTURE(count, bvh.node_count(), bvh.depth);
        REQUIRE(bvh.triangle_count() == std::size_t(count));
        REQUIRE(bvh.depth < detail::kBvhStackSize);
        detail::DeviceBvh dev(test::device(), bvh);
        std::uniform_real_distribution<float> u(-2.0f, 12.0f), tm(0.5f, 20.0f);
        std::vector<float> rays;
        for (int i = 0; i < 4000; ++i) {
            const glm::vec3 o(u(rng), u(rng), u(rng));
            // Half the rays aim at a point of a random triangle (near a corner or at the centroid), half anywhere.
            // Not at a vertex or edge exactly: there the device's contracted multiply-adds (OpenCL allows them)
            // may decide the other way than the host; the sphere test covers edges and vertices.
            glm::vec3 d = random_unit(rng);
            if (i % 2 == 0) {
                const glm::uvec3 t = mesh.triangles[std::size_t(rng()) % mesh.triangles.size()];
                const float w0 = i % 4 == 0 ? 0.9f : 1.0f / 3.0f, w1 = (1.0f - w0) / 2.0f;
                const glm::vec3 target = w0 * mesh.positions[t.x] + w1 * (mesh.positions[t.y] + mesh.positions[t.z]);
                if (glm::length(target - o) > 1e-3f) d = glm::normalize(target - o);
            }
            add_ray(rays, o, d, i % 3 == 0 ? tm(rng) : INFINITY);
        }
        std::vector<std::uint32_t> steps;
        const auto hits = dev.trace(rays, false, &steps);
        const auto any = dev.trace(rays, true);
        int hit_count = 0;
        for (std::size_t i = 0; i < hits.size(); ++i) {
            const glm::vec3 o(rays[8 * i], rays[8 * i + 1], rays[8 * i + 2]), d(rays[8 * i + 4], rays[8 * i + 5], rays[8 * i + 6]);
            const detail::RayHit ref = detail::intersect_brute_force(mesh, o, d, rays[8 * i + 3]);
            CAPTURE(i, ref.prim, ref.t, hits[i].prim, hits[i].t);
            REQUIRE((hits[i].prim >= 0) == (ref.prim >= 0));
            REQUIRE((any[i].prim >= 0) == (ref.prim >= 0));
            if (ref.prim < 0) continue;
            ++hit_count;
            // Same formula on both sides (bvh.cl switches FMA contraction off), but the compilers may still order
            // or fuse differently: t of a grazing ray (small determinant) is ill-conditioned, so 1e-4 relative; the
            // triangle may differ only where two lie at the same distance.
            REQUIRE(std::abs(hits[i].t - ref.t) <= 1e-4f * ref.t);
            if (hits[i].prim != ref.prim) {
                const glm::uvec3 t = mesh.triangles[std::size_t(hits[i].prim)];
                float tt, uu, vv;
                REQUIRE(detail::intersect_triangle(o, d, mesh.positions[t.x], mesh.positions[t.y], mesh.positions[t.z],
                                                   rays[8 * i + 3] * 1.001f, tt, uu, vv));
                REQUIRE(std::abs(tt - ref.t) <= 1e-4f * ref.t);
            } else {
                REQUIRE(std::abs(hits[i].u - ref.u) <= 1e-4f);
                REQUIRE(std::abs(hits[i].v - ref.v) <= 1e-4f);
            }
            REQUIRE(any[i].t <= rays[8 * i + 3]);
        }
        REQUIRE(hit_count > int(hits.size()) / 8);  // the targeted rays do hit
        // The renderer's llvmpipe loop budget assumes at most 32 steps per tree level (trace_loops in
        // render/renderer_impl.hpp).
        const auto worst = *std::max_element(steps.begin(), steps.end());
        CAPTURE(worst);
        REQUIRE(long(worst) <= 32L * bvh.depth);
    }
}

TEST_CASE("bvh: a closed sphere does not leak (rays through vertices and edges from inside)", "[bvh]") {
    const TriangleMesh sphere = test::icosphere(glm::vec3(0.3f, -0.2f, 0.1f), 5.0f, 4, 1);
    const detail::Bvh bvh = detail::build_bvh(sphere);
    detail::DeviceBvh dev(test::device(), bvh);
    std::mt19937 rng(5);
    std::vector<float> rays;
    const glm::vec3 inside(0.9f, 0.4f, -1.3f);
    // Through every vertex and every edge midpoint (the cases a non-watertight test misses), then random.
    for (const auto& p : sphere.positions) add_ray(rays, inside, glm::normalize(p - inside), INFINITY);
    for (const auto& t : sphere.triangles)
        add_ray(rays, inside, glm::normalize(0.5f * (sphere.positions[t.x] + sphere.positions[t.y]) - inside), INFINITY);
    for (int i = 0; i < 20000; ++i) add_ray(rays, inside, random_unit(rng), INFINITY);
    const auto hits = dev.trace(rays, false);
    for (std::size_t i = 0; i < hits.size(); ++i) {
        CAPTURE(i);
        REQUIRE(hits[i].prim >= 0);
        REQUIRE(hits[i].t > 0.0f);
        REQUIRE(hits[i].t < 12.0f);
    }
}

TEST_CASE("bvh: deterministic build, bounded depth on degenerate input, empty mesh misses", "[bvh]") {
    std::mt19937 rng(3);
    const TriangleMesh mesh = random_soup(rng, 500, 4.0f, 0.5f);
    const detail::Bvh a = detail::build_bvh(mesh), b = detail::build_bvh(mesh);
    // Bytes, not floats: the int fields stored in floats may be NaN patterns.
    REQUIRE(a.nodes.size() == b.nodes.size());
    REQUIRE(std::memcmp(a.nodes.data(), b.nodes.data(), a.nodes.size() * 4) == 0);
    REQUIRE(a.order == b.order);
    // 4096 copies of one triangle: no centroid extent, so every split is the median: depth ~ log2(4096 / 4) + 1.
    TriangleMesh same;
    same.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    same.normals.assign(3, {0, 0, 1});
    same.triangles.assign(4096, {0, 1, 2});
    same.materials.assign(4096, 1);
    const detail::Bvh d = detail::build_bvh(same);
    REQUIRE(d.depth <= 12);
    detail::DeviceBvh dd(test::device(), d);
    std::vector<float> rays;
    add_ray(rays, {0.2f, 0.2f, 5.0f}, {0, 0, -1}, INFINITY);
    add_ray(rays, {0.2f, 0.2f, 5.0f}, {0, 0, 1}, INFINITY);
    const auto h = dd.trace(rays, false);
    REQUIRE(h[0].prim >= 0);
    REQUIRE(std::abs(h[0].t - 5.0f) < 1e-5f);
    REQUIRE(h[1].prim < 0);
    const detail::Bvh empty = detail::build_bvh(TriangleMesh{});
    REQUIRE(empty.node_count() == 0);
    detail::DeviceBvh de(test::device(), empty);
    REQUIRE(de.trace(rays, false)[0].prim < 0);
}

// Small enough for the oclgrind stage: the traversal kernel (checked for out-of-bounds accesses, uninitialized
// reads and races), then the path tracer on a scene of blocks and triangles ([oclgrind-small]: without the
// uninitialized-value plugin, which crashes on the tracer's 3-vectors; tools/ci/oclgrind.sh).
TEST_CASE("bvh: traversal kernel at simulator size", "[bvh][oclgrind]") {
    std::mt19937 rng(9);
    const TriangleMesh mesh = random_soup(rng, 40, 6.0f, 1.0f);
    detail::DeviceBvh dev(test::device(), detail::build_bvh(mesh));
    std::vector<float> rays;
    for (int i = 0; i < 96; ++i) add_ray(rays, {3.0f, 3.0f, -4.0f}, random_unit(rng), i % 2 ? 8.0f : INFINITY);
    const auto hits = dev.trace(rays, false), any = dev.trace(rays, true);
    for (std::size_t i = 0; i < hits.size(); ++i) {
        const glm::vec3 o(rays[8 * i], rays[8 * i + 1], rays[8 * i + 2]), d(rays[8 * i + 4], rays[8 * i + 5], rays[8 * i + 6]);
        const detail::RayHit ref = detail::intersect_brute_force(mesh, o, d, rays[8 * i + 3]);
        REQUIRE((hits[i].prim >= 0) == (ref.prim >= 0));
        REQUIRE((any[i].prim >= 0) == (ref.prim >= 0));
    }
}

TEST_CASE("bvh: the path tracer on blocks and triangles at simulator size", "[bvh][render][oclgrind-small]") {
    VoxelScene s({8, 6, 8}, "blocks and triangles");
    const auto m = s.add_material({glm::vec3(0.6f), glm::vec3(0.0f), false});
    const auto lamp = s.add_material({glm::vec3(0.5f), glm::vec3(2.0f), false});
    s.fill({0, 0, 0}, {8, 1, 8}, m);
    s.mesh = test::box_mesh({2.5f, 1.5f, 2.5f}, {4.5f, 3.0f, 4.0f}, lamp);
    Renderer r(test::device(), s);
    CameraPose pose;
    pose.position = glm::vec3(5.5f, 2.5f, 6.0f);
    RenderSettings rs;
    rs.n = 4;
    rs.feature_spp = 1;
    rs.reference_spp = 2;
    rs.max_bounces = 2;
    const Frame f = r.render(pose, lighting_at(12.0f, 0.6f), rs);
    REQUIRE(test::all_finite(f.reference->data));
    const Image ao = r.render_ao(pose, rs, 4, 2.0f);
    REQUIRE(test::all_finite(ao.data));
    const Image geo = r.render_geometry(pose, rs, 1.0f);
    REQUIRE(test::all_finite(geo.data));
}
