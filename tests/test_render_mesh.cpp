// The path tracer on triangle meshes (kernels/bvh.cl under kernels/scene.cl) against exact cases: sunlight on
// a triangle floor with a block's shadow and on a block floor with a triangle box's shadow (blocks and triangles
// occlude each other), the lighting from an emissive triangle (Lambert's polygon formula), a closed sphere's
// furnace test (no leaks; Le / (1 - albedo)), and the AO of a floor point under a box.
#include <cmath>

#include <glm/glm.hpp>

#include "mesh_shapes.hpp"
#include "ngi/camera.hpp"
#include "ngi/render.hpp"
#include "ngi/scene.hpp"
#include "test_support.hpp"

using namespace ngi;

namespace {

// Entry distance of o + t d into the box [lo, hi], or a negative value when the ray misses it.
float ray_box(glm::vec3 o, glm::vec3 d, glm::vec3 lo, glm::vec3 hi) {
    float t0 = 0.0f, t1 = INFINITY;
    for (int a = 0; a < 3; ++a) {
        if (d[a] == 0.0f) {
            if (o[a] < lo[a] || o[a] > hi[a]) return -1.0f;
            continue;
        }
        float ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    return t0 <= t1 ? t0 : -1.0f;
}

// A camera at `position` whose front face looks straight down (-y), up = -z.
CameraPose looking_down(glm::vec3 position) {
    CameraPose pose;
    pose.position = position;
    pose.look = glm::vec3(0, -1, 0);
    pose.up = glm::vec3(0, 0, -1);
    return pose;
}

// The point of the plane y = y0 that pixel (x, y) of the front face of `pose` sees.
glm::vec3 plane_point(const CameraPose& pose, int x, int y, int n, float y0) {
    const FaceBasis b = CameraCluster::from_look_up(pose.look, pose.up).face(Face::Front);
    const glm::vec3 d = face_pixel_direction(b, x, y, n);
    return pose.position + d * ((y0 - pose.position.y) / d.y);
}

// A floor at height y0 seen from `pose` looking straight down, lit by a hard sun only: every pixel that sees the
// floor holds E cos / pi, or 0 where the box [lo, hi] shadows it; pixels that see the box (or within 0.05 m of the
// shadow's edge, where a pixel's point lies on the boundary) are skipped. Returns the pixels checked.
int check_sun_floor(const VoxelScene& scene, float y0, glm::vec3 lo, glm::vec3 hi) {
    Renderer r(test::device(), scene);
    const CameraPose pose = looking_down(glm::vec3(8.0f, 5.0f, 8.0f));
    Lighting light;
    light.sun.direction = glm::normalize(glm::vec3(0.35f, 1.0f, 0.2f));
    light.sun.irradiance = glm::vec3(2.0f, 1.5f, 1.0f);
    RenderSettings rs;
    rs.feature_spp = 8;  // noise is fine here: these checks are not about light quality
    rs.n = 32;
    rs.reference_spp = 2;
    rs.max_bounces = 0;
    const Image ref = r.render_reference(pose, light, rs);
    const FaceBasis b = CameraCluster::from_look_up(pose.look, pose.up).face(Face::Front);
    const float lit = light.sun.direction.y / float(M_PI);
    int checked = 0, shadowed = 0;
    for (int y = 0; y < rs.n; ++y)
        for (int x = 0; x < rs.n; ++x) {
            const glm::vec3 d = face_pixel_direction(b, x, y, rs.n);
            const float t_floor = (y0 - pose.position.y) / d.y;
            const float t_box = ray_box(pose.position, d, lo, hi);
            if (t_box >= 0.0f && t_box < t_floor) continue;  // the camera sees the box
            const glm::vec3 p = pose.position + d * t_floor;
            const glm::vec3 sd = light.sun.direction;
            const bool shadow = ray_box(p, sd, lo, hi) >= 0.0f;
            const bool near_edge = (ray_box(p, sd, lo - 0.05f, hi + 0.05f) >= 0.0f) != shadow ||
                                   (ray_box(p, sd, lo + 0.05f, hi - 0.05f) >= 0.0f) != shadow;
            if (near_edge) continue;
            CAPTURE(x, y, p.x, p.z, shadow);
            for (int c = 0; c < 3; ++c) {
                const float expect = shadow ? 0.0f : light.sun.irradiance[c] * lit;
                REQUIRE(std::abs(ref.at(c, y, x) - expect) <= 1e-5f * (1.0f + expect));
            }
            ++checked;
            shadowed += shadow;
        }
    REQUIRE(shadowed > 10);
    return checked;
}

}  // namespace

TEST_CASE("mesh render: sunlight on triangles and blocks, each shadowing the other", "[render][mesh]") {
    {  // a triangle floor (y = 1) and a block standing on it
        VoxelScene s({16, 8, 16}, "triangle floor");
        const auto m = s.add_material({glm::vec3(0.5f), glm::vec3(0.0f), false});
        s.mesh.positions = {{0, 1, 0}, {16, 1, 0}, {16, 1, 16}, {0, 1, 16}};
        s.mesh.normals.assign(4, {0, 1, 0});
        s.mesh.triangles = {{0, 2, 1}, {0, 3, 2}};
        s.mesh.materials = {m, m};
        s.fill({9, 1, 9}, {11, 3, 11}, m);
        REQUIRE(check_sun_floor(s, 1.0f, {9, 1, 9}, {11, 3, 11}) > 600);
    }
    {  // a block floor (top at y = 1) and a triangle box above it
        VoxelScene s({16, 8, 16}, "block floor");
        const auto m = s.add_material({glm::vec3(0.5f), glm::vec3(0.0f), false});
        s.fill({0, 0, 0}, {16, 1, 16}, m);
        s.mesh = test::box_mesh({9.0f, 1.5f, 9.0f}, {11.0f, 3.0f, 11.5f}, m);
        REQUIRE(check_sun_floor(s, 1.0f, {9.0f, 1.5f, 9.0f}, {11.0f, 3.0f, 11.5f}) > 600);
    }
}

TEST_CASE("mesh render: lighting from an emissive triangle follows Lambert's polygon formula", "[render][mesh]") {
    VoxelScene s({16, 8, 16}, "emissive triangle");
    const auto floor = s.add_material({glm::vec3(0.0f), glm::vec3(0.0f), false});
    const float L = 5.0f;
    const auto lamp = s.add_material({glm::vec3(0.0f), glm::vec3(L), false});
    s.fill({0, 0, 0}, {16, 1, 16}, floor);
    const std::vector<glm::vec3> tri = {{6.0f, 3.0f, 6.5f}, {10.5f, 3.5f, 7.0f}, {7.5f, 2.5f, 10.5f}};
    s.mesh.positions = tri;
    s.mesh.normals.assign(3, {0, -1, 0});
    s.mesh.triangles = {{0, 1, 2}};
    s.mesh.materials = {lamp};
    Renderer r(test::device(), s);
    const CameraPose pose = looking_down(glm::vec3(8.0f, 2.0f, 8.0f));
    RenderSettings rs;
    rs.feature_spp = 8;  // noise is fine here: these checks are not about light quality
    rs.n = 8;
    rs.reference_spp = 8192;
    rs.max_bounces = 0;
    rs.seed = 11;
    Image var;
    const Image ref = r.render_reference(pose, Lighting{}, rs, &var);
    double worst_z = 0;
    for (int y = 0; y < rs.n; ++y)
        for (int x = 0; x < rs.n; ++x) {
            const glm::vec3 p = plane_point(pose, x, y, rs.n, 1.0f);
            const double expect =
                L * test::polygon_form_factor(glm::dvec3(p), {0, 1, 0}, {glm::dvec3(tri[0]), glm::dvec3(tri[1]), glm::dvec3(tri[2])});
            const double err = std::abs(ref.at(0, y, x) - expect), sigma = std::sqrt(double(var.at(0, y, x)));
            CAPTURE(x, y, expect, ref.at(0, y, x), sigma);
            REQUIRE(expect > 0.05);
            REQUIRE(err <= 5.0 * sigma + 1e-4);
            worst_z = std::max(worst_z, err / sigma);
        }
    WARN("emissive triangle: worst |error| / stderr over 64 pixels = " << worst_z);
}

TEST_CASE("mesh render: furnace inside a closed sphere (no leaks, Le / (1 - albedo))", "[render][mesh]") {
    VoxelScene s({12, 12, 12}, "furnace");
    const float a = 0.5f, Le = 0.75f;
    const auto m = s.add_material({glm::vec3(a), glm::vec3(Le), false});
    s.mesh = test::icosphere(glm::vec3(6.0f), 5.0f, 3, m);
    Renderer r(test::device(), s);
    CameraPose pose;
    pose.position = glm::vec3(6.3f, 5.8f, 6.1f);
    Lighting sky;  // a bright sky: any ray that leaked out would bring it in
    sky.sky.zenith = sky.sky.horizon = sky.sky.ground = glm::vec3(100.0f);
    RenderSettings rs;
    rs.feature_spp = 8;  // noise is fine here: these checks are not about light quality
    rs.n = 8;
    rs.feature_spp = 4;
    rs.reference_spp = 512;
    rs.max_bounces = 12;  // a^13 = 1e-4 of the sum is cut off (the expectation below accounts for it)
    const Frame f = r.render(pose, sky, rs);
    for (int face = 0; face < kFaceCount; ++face) {
        const Image& direct = f.get(Feature::Direct, Face(face));
        const Image& normal = f.get(Feature::Normal, Face(face));
        const Image& depth = f.get(Feature::Depth, Face(face));
        for (std::size_t i = 0; i < direct.data.size(); ++i) REQUIRE(direct.data[i] == Le);  // every ray hits
        for (int y = 0; y < rs.n; ++y)
            for (int x = 0; x < rs.n; ++x) {
                // The shading normal faces the camera, i.e. points inward, close to the radial direction.
                const glm::vec3 nv(normal.at(0, y, x), normal.at(1, y, x), normal.at(2, y, x));
                REQUIRE(std::abs(glm::length(nv) - 1.0f) < 1e-4f);
                REQUIRE(depth.at(0, y, x) > 2.0f);
                REQUIRE(depth.at(0, y, x) < 6.0f);
            }
    }
    REQUIRE(f.reference);
    double mean = 0;
    for (float v : f.reference->data) mean += v;
    mean /= double(f.reference->data.size());
    const double expect = Le * (1.0 - std::pow(a, rs.max_bounces + 1)) / (1.0 - a);  // = 1.5
    CAPTURE(mean, expect);
    REQUIRE(std::abs(mean - expect) < 0.02 * expect);
}

TEST_CASE("mesh render: AO of a floor under a triangle box = 1 - the box bottom's form factor", "[render][mesh][ao]") {
    VoxelScene s({16, 10, 16}, "box over floor");
    const auto m = s.add_material({glm::vec3(0.5f), glm::vec3(0.0f), false});
    s.fill({0, 0, 0}, {16, 1, 16}, m);  // floor top at y = 1
    const glm::vec3 lo(6.0f, 3.0f, 6.5f), hi(10.0f, 5.0f, 9.5f);
    s.mesh = test::box_mesh(lo, hi, m);
    Renderer r(test::device(), s);
    const CameraPose pose = looking_down(glm::vec3(8.0f, 2.0f, 8.0f));
    RenderSettings rs;
    rs.feature_spp = 8;  // noise is fine here: these checks are not about light quality
    rs.n = 8;
    rs.seed = 3;
    const int rays = 8192;
    const Image ao = r.render_ao(pose, rs, rays, INFINITY);
    const std::vector<glm::dvec3> bottom = {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, lo.y, hi.z}, {lo.x, lo.y, hi.z}};
    for (int y = 0; y < rs.n; ++y)
        for (int x = 0; x < rs.n; ++x) {
            const glm::vec3 p = plane_point(pose, x, y, rs.n, 1.0f);
            // From below the box, a ray that meets the box crosses its bottom face first (module docs above).
            const double expect = 1.0 - test::polygon_form_factor(glm::dvec3(p), {0, 1, 0}, bottom);
            const double sigma = std::sqrt(expect * (1.0 - expect) / rays);
            CAPTURE(x, y, expect, ao.at(0, y, x));
            REQUIRE(std::abs(ao.at(0, y, x) - expect) <= 5.0 * sigma + 1e-4);
        }
}

TEST_CASE("mesh render: surface ids and barycentric weights reproduce the visible point", "[render][mesh]") {
    VoxelScene s({16, 10, 16}, "box over floor");
    const auto m = s.add_material({glm::vec3(0.5f), glm::vec3(0.0f), false});
    s.fill({0, 0, 0}, {16, 1, 16}, m);
    s.mesh = test::box_mesh({6.0f, 3.0f, 6.5f}, {10.0f, 5.0f, 9.5f}, m);
    Renderer r(test::device(), s);
    CameraPose pose;
    pose.position = glm::vec3(13.0f, 7.0f, 14.0f);
    pose.look = glm::normalize(glm::vec3(8.0f, 3.0f, 8.0f) - pose.position);
    RenderSettings rs;
    rs.feature_spp = 8;  // noise is fine here: these checks are not about light quality
    rs.n = 32;
    const Image surf = r.render_surface(pose, rs);
    const Image geo = r.render_geometry(pose, rs, 0.0f);
    const FaceBasis b = CameraCluster::from_look_up(pose.look, pose.up).face(Face::Front);
    int on_mesh = 0, on_blocks = 0;
    for (int y = 0; y < rs.n; ++y)
        for (int x = 0; x < rs.n; ++x) {
            const glm::vec3 d = face_pixel_direction(b, x, y, rs.n);
            const float depth = geo.at(6, y, x);
            if (surf.at(0, y, x) < 0.0f) {
                ++on_blocks;
                REQUIRE(surf.at(3, y, x) == 0.0f);
                continue;
            }
            ++on_mesh;
            // The weighted vertices = the point at the pixel's planar depth along its ray.
            glm::vec3 p(0.0f);
            float wsum = 0;
            for (int k = 0; k < 3; ++k) {
                const float idx = surf.at(k, y, x), w = surf.at(3 + k, y, x);
                REQUIRE(idx == std::floor(idx));
                REQUIRE(w >= -1e-6f);
                p += w * s.mesh.positions[std::size_t(idx)];
                wsum += w;
            }
            REQUIRE(std::abs(wsum - 1.0f) < 1e-5f);
            const glm::vec3 seen = pose.position + d * (depth / glm::dot(d, b.look));
            CAPTURE(x, y);
            REQUIRE(glm::length(p - seen) < 1e-3f);
        }
    REQUIRE(on_mesh >= 25);
    REQUIRE(on_blocks >= 25);
}
