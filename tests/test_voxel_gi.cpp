// ngi::VoxelGi (ngi/voxel_gi.hpp), the public face of the LTF and probe shading over a scene's surface voxels: its
// LTF equals the double reference on a real scene's voxels, a rendered frame lit from the path-traced field matches
// the path-traced reference where the field is exact (a floor under a uniform sky), and bad input is refused by name.
#include <catch2/catch.hpp>
#include <cmath>

#include "ngi/camera.hpp"
#include "ngi/error.hpp"
#include "ngi/render.hpp"
#include "ngi/scene.hpp"
#include "ngi/voxel_field.hpp"
#include "ngi/voxel_gi.hpp"
#include "reference_voxel.hpp"
#include "test_support.hpp"

using namespace ngi;

namespace {

// A floor slab (with a block on it, so that voxels shade each other) under a uniform sky of radiance L: every
// upward face of the open floor receives irradiance pi L from the sky alone, lighting L.
VoxelScene floor_scene() {
    VoxelScene s({9, 4, 9}, "floor");
    const std::uint8_t grey = s.add_material({glm::vec3(0.5f), glm::vec3(0.0f), false});
    s.fill({0, 0, 0}, {9, 1, 9}, grey);
    s.fill({6, 1, 6}, {8, 3, 8}, s.add_material({glm::vec3(0.7f, 0.2f, 0.1f), glm::vec3(0.0f), false}));
    return s;
}

Lighting uniform_sky(glm::vec3 L) {
    Lighting l;
    l.sky.zenith = l.sky.horizon = l.sky.ground = L;
    return l;
}

test::LtfScene ltf_scene(const SurfaceVoxels& v, const std::vector<float>& direct) {
    test::LtfScene s;
    s.voxels = int(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) {
        const float* a = &v.attributes[i * kVoxelAttributes];
        s.position.insert(s.position.end(), {v.probe[i].x, v.probe[i].y, v.probe[i].z, 0.0f});
        s.normal.insert(s.normal.end(), {v.normal[i].x, v.normal[i].y, v.normal[i].z, 0.0f});
        s.albedo.insert(s.albedo.end(), {a[3], a[4], a[5], 0.0f});
        s.direct.insert(s.direct.end(), {direct[3 * i], direct[3 * i + 1], direct[3 * i + 2], 0.0f});
        s.exposed.push_back(v.exposed[i]);
    }
    return s;
}

}  // namespace

TEST_CASE("voxel GI: the LTF of a scene's voxels equals the double reference, both variants", "[voxel_gi]") {
    const VoxelScene scene = floor_scene();
    const Lighting l = uniform_sky(glm::vec3(0.2f, 0.5f, 1.0f));
    const SurfaceVoxels v = surface_voxels(test::device(), scene, l);
    Renderer r(test::device(), scene);
    VoxelFieldSettings vs;
    vs.directions = 16;
    vs.point_samples = 16;
    vs.max_bounces = 0;
    const VoxelField f = r.render_voxel_field(v, l, vs);
    const std::vector<std::uint32_t> vis = r.voxel_visibility(v);
    VoxelGi gi(test::device(), v);
    CHECK(gi.voxels() == v.size());
    CHECK(gi.grid() == scene.size);
    CHECK(gi.ltf(f.direct, 0, LtfVariant::Physical) == f.direct);  // no bounce: the direct light itself
    const test::LtfScene ref_scene = ltf_scene(v, f.direct);
    for (const bool physical : {true, false}) {
        INFO((physical ? "physical" : "as written"));
        const std::vector<std::uint32_t>* mask = physical ? &vis : nullptr;
        std::vector<double> energy;
        const std::vector<float> got =
            gi.ltf(f.direct, 3, physical ? LtfVariant::Physical : LtfVariant::AsWritten, mask, &energy);
        const std::vector<double> want = test::ltf_reference(ref_scene, 3, physical, mask);
        REQUIRE(got.size() == 3 * v.size());
        CHECK(energy.size() == 4);
        double worst = 0;
        for (std::size_t i = 0; i < v.size(); ++i)
            for (int c = 0; c < 3; ++c) {
                const double w = want[4 * i + std::size_t(c)];
                worst = std::max(worst, std::abs(got[3 * i + std::size_t(c)] - w) / (1e-6 + std::abs(w)));
            }
        // float sums over ~200 senders against double: a few ulp per term (docs/VOXEL_LTF.md)
        CHECK(worst < 1e-4);
    }
}

TEST_CASE("voxel GI: a frame lit from the path-traced field matches the reference where the field is exact",
          "[voxel_gi]") {
    const VoxelScene scene = floor_scene();
    const glm::vec3 L(0.2f, 0.5f, 1.0f);
    const Lighting l = uniform_sky(L);
    const SurfaceVoxels v = surface_voxels(test::device(), scene, l);
    Renderer r(test::device(), scene);
    VoxelFieldSettings vs;
    vs.directions = 256;
    vs.point_samples = 64;
    vs.max_bounces = 2;
    const VoxelField f = r.render_voxel_field(v, l, vs);
    // Looking straight down at the open part of the floor from 2.5 m above it.
    CameraPose pose;
    pose.position = glm::vec3(2.5f, 3.5f, 2.5f);
    pose.look = glm::vec3(0, -1, 0);
    pose.up = glm::vec3(0, 0, -1);
    RenderSettings rs;
    rs.feature_spp = 8;  // noise is fine here: these checks are not about light quality
    rs.n = 16;
    rs.reference_spp = 64;
    rs.max_bounces = 2;
    const Frame frame = r.render(pose, l, rs);
    VoxelGi gi(test::device(), v);
    ShadeStats st;
    const Image from_sh = gi.shade(frame, pose.position, Face::Front, f.sh, VoxelFieldKind::Sh, &st);
    CHECK(st.no_voxel == 0);
    CHECK(st.non_finite == 0);
    const Image from_lighting = gi.shade(frame, pose.position, Face::Front, f.lighting, VoxelFieldKind::Lighting);
    REQUIRE(from_sh.width == 16);
    // Pixels near the view's centre see open floor, far (> 1.5 m) from the block: lighting L there, up to the
    // band-2 truncation of the hemisphere (under 1 % toward its axis) and the projection's noise at M = 256.
    int checked = 0;
    for (int y = 5; y < 11; ++y)
        for (int x = 5; x < 11; ++x)
            for (int c = 0; c < 3; ++c) {
                const float want = L[c];
                CHECK(from_sh.at(c, y, x) == Approx(want).epsilon(0.08));
                CHECK(from_lighting.at(c, y, x) == Approx(want).epsilon(0.08));
                CHECK(frame.reference->at(c, y, x) == Approx(want).epsilon(0.15));  // 64 spp
                ++checked;
            }
    CHECK(checked == 108);
}

TEST_CASE("voxel GI: bad input is refused naming what is wrong", "[voxel_gi]") {
    const VoxelScene scene = floor_scene();
    const Lighting l = uniform_sky(glm::vec3(1.0f));
    const SurfaceVoxels v = surface_voxels(test::device(), scene, l);
    VoxelGi gi(test::device(), v);
    const std::size_t V = v.size();
    std::vector<float> direct(3 * V, 0.5f);
    CHECK_THROWS_AS(gi.ltf(std::vector<float>(3 * V - 1, 0.0f), 1, LtfVariant::Physical), InputError);
    direct[7] = NAN;
    CHECK_THROWS_WITH(gi.ltf(direct, 1, LtfVariant::Physical), Catch::Contains("voxel 2 channel 1 is not finite"));
    direct[7] = 0.5f;
    const std::vector<std::uint32_t> mask(V * ((V + 31) / 32), ~0u);
    CHECK_THROWS_WITH(gi.ltf(direct, 1, LtfVariant::AsWritten, &mask), Catch::Contains("no shadow term"));
    const std::vector<std::uint32_t> short_mask(3, 0u);
    CHECK_THROWS_WITH(gi.ltf(direct, 1, LtfVariant::Physical, &short_mask), Catch::Contains("visibility mask"));
    CHECK_THROWS_AS(gi.ltf(direct, 65, LtfVariant::Physical), InputError);  // beyond 64 bounces

    Renderer r(test::device(), scene);
    RenderSettings rs;
    rs.feature_spp = 8;  // noise is fine here: these checks are not about light quality
    rs.n = 8;
    rs.reference = false;
    const Frame frame = r.render(CameraPose{{4.5f, 2.5f, 4.5f}, {0, -1, 0}, {0, 0, -1}}, l, rs);
    CHECK_THROWS_WITH(gi.shade(frame, {4.5f, 2.5f, 4.5f}, Face::Front, std::vector<float>(27 * V - 27, 0.0f),
                               VoxelFieldKind::Sh),
                      Catch::Contains("SH field of"));
    std::vector<float> sh(27 * V, 0.1f);
    sh[27 * 3 + 4] = INFINITY;
    CHECK_THROWS_WITH(gi.shade(frame, {4.5f, 2.5f, 4.5f}, Face::Front, sh, VoxelFieldKind::Sh),
                      Catch::Contains("coefficient 4 of voxel 3 is not finite"));
    CHECK_THROWS_WITH(gi.shade(frame, {NAN, 2.5f, 4.5f}, Face::Front, direct, VoxelFieldKind::Lighting),
                      Catch::Contains("camera position is not finite"));
    Frame broken = frame;
    broken.get(Feature::Depth, Face::Front) = Image(4, 4, 1);
    CHECK_THROWS_WITH(gi.shade(broken, {4.5f, 2.5f, 4.5f}, Face::Front, direct, VoxelFieldKind::Lighting),
                      Catch::Contains("depth and normal of the front face"));
    SurfaceVoxels bad = v;
    bad.probe.pop_back();
    CHECK_THROWS_WITH(VoxelGi(test::device(), bad), Catch::Contains("inconsistent surface voxels"));
}
