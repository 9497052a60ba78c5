// ngi::SceneVoxels (ngi/scene_voxels.hpp), seed 004 on one scene at one time of day: every method gives what the
// step-by-step calls it names give, bit for bit, and it refuses a time that is not one and a face a frame lacks; and
// ngi::unpack_frame_planes (ngi/pipeline.hpp), the inverse of pack_frame_planes. The C ABI's ngi_voxels and
// ngi_frame_from_planes are these (tests/c/test_c_api.c covers them through C).
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "ngi/error.hpp"
#include "ngi/pipeline.hpp"
#include "ngi/scene_voxels.hpp"
#include "test_support.hpp"

using namespace ngi;

namespace {

// A floor slab with a block on it (so that voxels shade each other), lit by lighting_at.
VoxelScene slab_scene() {
    VoxelScene s({8, 4, 8}, "slab");
    const std::uint8_t grey = s.add_material({glm::vec3(0.5f), glm::vec3(0.0f), false});
    s.fill({0, 0, 0}, {8, 1, 8}, grey);
    s.fill({5, 1, 5}, {7, 3, 7}, s.add_material({glm::vec3(0.7f, 0.2f, 0.1f), glm::vec3(0.0f), false}));
    s.default_time = 10.5f;
    return s;
}

Frame random_frame(int n, bool emission, bool env) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-2.0f, 2.0f);
    Frame f;
    f.n = n;
    f.look = glm::normalize(glm::vec3(0.3f, -0.2f, -1.0f));
    f.up = glm::vec3(0, 1, 0);
    for (int k = 0; k < kFeatureCount; ++k) {
        if ((Feature(k) == Feature::Emission && !emission) || (Feature(k) == Feature::Env && !env)) continue;
        for (int face = 0; face < kFaceCount; ++face) {
            Image im(n, n, feature_channels(Feature(k)));
            for (float& v : im.data) v = u(rng);
            f.get(Feature(k), Face(face)) = std::move(im);
        }
    }
    return f;
}

}  // namespace

TEST_CASE("frame planes: unpack_frame_planes inverts pack_frame_planes, six faces or the front one", "[frame_planes]") {
    for (const bool emission : {false, true}) {
        const Frame f = random_frame(5, emission, !emission);
        const std::vector<float> planes = pack_frame_planes(f, kFaceCount);
        const FrameDesc desc = FrameDesc::of(f, kFaceCount);
        const Frame back = unpack_frame_planes(planes.data(), 5, desc);
        CHECK(back.n == 5);
        CHECK(back.look == f.look);
        CHECK(back.up == f.up);
        for (int k = 0; k < kFeatureCount; ++k)
            for (int face = 0; face < kFaceCount; ++face) {
                const Image& a = f.get(Feature(k), Face(face));
                const Image& b = back.get(Feature(k), Face(face));
                CHECK(b.data == a.data);  // an absent optional feature stays absent (empty)
                if (!a.data.empty()) CHECK((b.width == 5 && b.height == 5 && b.channels == a.channels));
            }
        CHECK(pack_frame_planes(back, kFaceCount) == planes);

        FrameDesc front = desc;
        front.faces = 1;
        const Frame one = unpack_frame_planes(planes.data(), 5, front);  // the front face leads the planes
        CHECK(one.get(Feature::Depth, Face::Front).data == f.get(Feature::Depth, Face::Front).data);
        CHECK(one.get(Feature::Depth, Face::Back).data.empty());
        CHECK(pack_frame_planes(one, 1) == pack_frame_planes(f, 1));
    }
    const std::vector<float> planes(frame_planes_bytes(4, kFaceCount) / sizeof(float), 0.0f);
    FrameDesc bad;
    bad.faces = 2;
    CHECK_THROWS_AS(unpack_frame_planes(planes.data(), 4, bad), InputError);
    CHECK_THROWS_AS(unpack_frame_planes(planes.data(), 0, FrameDesc{}), InputError);
    CHECK_THROWS_AS(unpack_frame_planes(nullptr, 4, FrameDesc{}), InputError);
}

TEST_CASE("scene voxels: each method gives the step-by-step calls' results bit for bit", "[scene_voxels]") {
    const VoxelScene scene = slab_scene();
    SceneVoxels sv(test::device(), scene, -1.0f);  // negative: the scene's own time
    CHECK(sv.hours() == scene.default_time);
    const Lighting l = lighting_at(scene.default_time, scene.sun_azimuth);
    CHECK(sv.lighting().sun.direction == l.sun.direction);
    CHECK(sv.lighting().sky.zenith == l.sky.zenith);
    CHECK(sv.scene().size == scene.size);

    const SurfaceVoxels v = surface_voxels(test::device(), scene, l);
    REQUIRE(sv.surface().size() == v.size());
    CHECK(sv.surface().attributes == v.attributes);
    CHECK(sv.surface().grid == v.grid);

    Renderer r(test::device(), scene);
    VoxelFieldSettings vs;
    vs.directions = 16;
    vs.sun_rays = 4;
    vs.point_samples = 8;
    vs.max_bounces = 1;
    vs.seed = 3;
    const VoxelField got = sv.field(vs), want = r.render_voxel_field(v, l, vs);
    CHECK(got.sh == want.sh);
    CHECK(got.direct == want.direct);
    CHECK(got.lighting == want.lighting);

    VoxelGi gi(test::device(), v);
    const std::vector<std::uint32_t> mask = r.voxel_visibility(v);
    CHECK(sv.ltf(want.direct, 2, LtfVariant::Physical, true) == gi.ltf(want.direct, 2, LtfVariant::Physical, &mask));
    CHECK(sv.ltf(want.direct, 2, LtfVariant::AsWritten, false) == gi.ltf(want.direct, 2, LtfVariant::AsWritten));

    CameraPose pose;
    pose.position = glm::vec3(2.5f, 3.0f, 2.5f);
    pose.look = glm::vec3(0, -1, 0);
    pose.up = glm::vec3(0, 0, -1);
    RenderSettings rs;
    rs.n = 8;
    rs.feature_spp = 2;
    rs.reference = false;
    rs.seed = 5;
    const Frame frame = sv.render(pose, rs);
    const Frame step = r.render(pose, l, rs);
    REQUIRE(frame.position.has_value());
    CHECK(*frame.position == pose.position);
    for (int k = 0; k < kFeatureCount; ++k)
        for (int face = 0; face < kFaceCount; ++face)
            CHECK(frame.get(Feature(k), Face(face)).data == step.get(Feature(k), Face(face)).data);

    CHECK(sv.shade(frame, pose.position, Face::Down, want.lighting, VoxelFieldKind::Lighting).data ==
          gi.shade(frame, pose.position, Face::Down, want.lighting, VoxelFieldKind::Lighting).data);
    CHECK(sv.shade(frame, pose.position, Face::Front, want.sh, VoxelFieldKind::Sh).data ==
          gi.shade(frame, pose.position, Face::Front, want.sh, VoxelFieldKind::Sh).data);
}

TEST_CASE("scene voxels: a time that is not one and a face the frame lacks are refused by name", "[scene_voxels]") {
    const VoxelScene scene = slab_scene();
    CHECK_THROWS_WITH(SceneVoxels(test::device(), scene, 24.5f), Catch::Contains("is not a time of day"));
    CHECK_THROWS_AS(SceneVoxels(test::device(), scene, std::nanf("")), InputError);
    SceneVoxels sv(test::device(), scene, 12.0f);
    CHECK(sv.hours() == 12.0f);
    CameraPose pose;
    pose.position = glm::vec3(2.5f, 3.0f, 2.5f);
    RenderSettings rs;
    rs.n = 4;
    rs.feature_spp = 1;
    rs.reference = false;
    Frame front_only = sv.render(pose, rs);
    for (int k = 0; k < kFeatureCount; ++k)
        for (int face = 1; face < kFaceCount; ++face) front_only.get(Feature(k), Face(face)) = Image();
    const std::vector<float> field(sv.surface().size() * 3, 0.5f);
    CHECK(sv.shade(front_only, pose.position, Face::Front, field, VoxelFieldKind::Lighting).width == 4);
    CHECK_THROWS_WITH(sv.shade(front_only, pose.position, Face::Back, field, VoxelFieldKind::Lighting),
                      Catch::Equals("the frame has no back face"));
}
