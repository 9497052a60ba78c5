// MagicaVoxel .vox files made to hurt the loader: deep and exponentially shared scene graphs, translations that
// overflow, counts far beyond the file's bytes. Each gives a clean InputError quickly (or a bounded scene), never a
// crash, a hang or gigabytes of memory. The limits are the kMaxVox* constants of ngi/scene.hpp.
#include <catch2/catch.hpp>
#include <climits>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "io_test_support.hpp"
#include "ngi/area_light.hpp"
#include "ngi/error.hpp"
#include "ngi/scene.hpp"
#include "vox_writer.hpp"

using namespace ngi;
using namespace vox_test;
namespace fs = std::filesystem;
using Catch::Matchers::Contains;

namespace {

const std::string kName = "hostile.vox";

// The InputError message of parse_vox, or "" if it loaded; `seconds` gets the CPU time it took (CPU, not wall
// time: the test machine may be shared, and sanitizer builds are slower, so the bounds below are generous).
std::string vox_error(const std::string& bytes, double* seconds = nullptr) {
    const std::clock_t t0 = std::clock();
    std::string e;
    try {
        parse_vox(bytes, kName);
    } catch (const InputError& x) {
        e = x.what();
    }
    if (seconds) *seconds = double(std::clock() - t0) / CLOCKS_PER_SEC;
    return e;
}

const std::string kCube = size_chunk(1, 1, 1) + xyzi({{0, 0, 0, 1}});  // model 0: one voxel

// A path of `nodes` scene-graph nodes from the root: nTRN, nGRP, nTRN, ... and a final nSHP of model 0.
std::string chain(int nodes, const Dict& frame = {}) {
    std::string g;
    for (int i = 0; i + 1 < nodes; ++i) g += i % 2 == 0 ? ntrn(i, i + 1, frame) : ngrp(i, {i + 1});
    return vox_file(kCube + g + nshp(nodes - 1, 0));
}

// `levels` groups, each listing its child twice: 2^levels paths to the leaf, in a file of a few hundred bytes.
// The leaf is a shape of model 0, or an empty group (no instance at all, only the walk).
std::string doubling(int levels, bool shape_leaf = true) {
    std::string g;
    for (int l = 0; l < levels; ++l) g += ntrn(2 * l, 2 * l + 1) + ngrp(2 * l + 1, {2 * l + 2, 2 * l + 2});
    const int leaf = 2 * levels;
    g += shape_leaf ? ntrn(leaf, leaf + 1) + nshp(leaf + 1, 0) : ngrp(leaf, {});
    return vox_file(kCube + g);
}

// Model 0 placed at each translation ("x y z") under one root group.
std::string placed_at(const std::vector<std::string>& ts) {
    std::vector<int> kids;
    std::string g;
    for (std::size_t i = 0; i < ts.size(); ++i) {
        const int t = 2 + 2 * int(i);
        kids.push_back(t);
        g += ntrn(t, t + 1, {{"_t", ts[i]}}) + nshp(t + 1, 0);
    }
    return vox_file(kCube + ntrn(0, 1) + ngrp(1, kids) + g);
}

}  // namespace

TEST_CASE(".vox hostile: deep scene graphs are refused without recursion", "[vox]") {
    // The limit itself: kMaxVoxDepth nodes on a path load, one more does not.
    const VoxelScene ok = parse_vox(chain(kMaxVoxDepth), kName);
    CHECK(ok.solid_count() == 1);
    CHECK_THAT(vox_error(chain(kMaxVoxDepth + 1)),
               Catch::Contains("read hostile.vox: scene graph deeper than 64 levels"));
    // The probe's file: ~20,000 levels used to overflow the call stack of the recursive walk.
    double t = 0.0;
    const std::string deep = chain(20000);
    CHECK_THAT(vox_error(deep, &t), Catch::Contains("scene graph deeper than 64 levels"));
    CHECK(t < 1.0);
}

TEST_CASE(".vox hostile: groups listing a child twice do not explode", "[vox]") {
    // A little sharing is a valid scene: 2^3 instances of one voxel at the same place.
    const VoxelScene few = parse_vox(doubling(3), kName);
    CHECK(few.size == glm::ivec3(1));
    CHECK(few.solid_count() == 1);
    // Depth 24 took 107 s and 937 MB before; deeper ones died of bad_alloc. Now the walk stops at its visit budget
    // whether or not the leaves place anything.
    for (int levels : {24, 30}) {
        for (bool shape_leaf : {true, false}) {
            INFO(levels << " levels, " << (shape_leaf ? "shape" : "empty group") << " leaves");
            const std::string f = doubling(levels, shape_leaf);
            CHECK(f.size() < 5000);
            double t = 0.0;
            const std::string e = vox_error(f, &t);
            CHECK_THAT(e, Catch::Contains("read hostile.vox: ") &&
                              (Catch::Contains("node visits") || Catch::Contains("model instances")));
            CHECK(t < 1.0);
        }
    }
}

TEST_CASE(".vox hostile: shared nodes that are not cycles still load, cycles are named", "[vox]") {
    // nSHP 3 is reached through two transforms: a DAG, two instances.
    const std::string dag = vox_file(kCube + ntrn(0, 1) + ngrp(1, {2, 4}) + ntrn(2, 3, {{"_t", "0 0 0"}}) + nshp(3, 0) +
                                     ntrn(4, 3, {{"_t", "3 0 0"}}));
    const VoxelScene s = parse_vox(dag, kName);
    CHECK(s.size == glm::ivec3(4, 1, 1));
    CHECK(s.solid_count() == 2);
    CHECK(s.solid({0, 0, 0}));
    CHECK(s.solid({3, 0, 0}));
    // A node reached from itself, deep down, and a group that lists itself.
    std::string back;
    for (int i = 0; i < 10; ++i) back += i % 2 == 0 ? ntrn(i, i + 1) : ngrp(i, {i + 1});
    back += ngrp(10, {0});
    CHECK_THAT(vox_error(vox_file(kCube + back)), Catch::Contains("scene graph has a cycle at node 0"));
    CHECK_THAT(vox_error(vox_file(kCube + ntrn(0, 1) + ngrp(1, {1}))), Catch::Contains("cycle at node 1"));
}

TEST_CASE(".vox hostile: translations beyond the coordinate range are refused, not wrapped", "[vox]") {
    // The probe's file gave a scene of "-2147483648 x 12 x -2147483648 blocks" from int overflow.
    for (const char* t : {"2147483647 0 0", "-2147483648 12 -2147483648", "99999999999999999999 0 0", "0 0 -1048577"}) {
        INFO(t);
        CHECK_THAT(vox_error(placed_at({t})),
                   Catch::Contains("read hostile.vox: translation '") && Catch::Contains("beyond +-1048576 blocks"));
    }
    for (const char* t : {"1 2", "1 2 3 4", "a b c", "1.5 0 0", ""}) {
        INFO("'" << t << "'");
        CHECK_THAT(vox_error(placed_at({t})), Catch::Contains("bad translation"));
    }
    // Each step in range, the sum not: two nested transforms of 10^6.
    CHECK_THAT(vox_error(chain(4, {{"_t", "1000000 0 0"}})),
               Catch::Contains("scene graph places node") && Catch::Contains("(2000000, 0, 0)"));
    // At the limit it loads (one block, wherever it is) and so do "+" signs and extra spaces.
    CHECK(parse_vox(placed_at({"1048576 -1048576 +1048576"}), kName).size == glm::ivec3(1));
    CHECK(parse_vox(placed_at({" 5  6 7 "}), kName).size == glm::ivec3(1));
    // The extent: 4096 blocks per axis load, 4097 do not (however few blocks in all).
    const VoxelScene wide = parse_vox(placed_at({"0 0 0", "4095 0 0"}), kName);
    CHECK(wide.size == glm::ivec3(kMaxVoxAxis, 1, 1));
    CHECK(wide.solid_count() == 2);
    CHECK_THAT(vox_error(placed_at({"0 0 0", "0 4096 0"})),
               Catch::Contains("1 x 4097 x 1 blocks exceeds the budget of 67108864 blocks, 4096 per axis"));
    CHECK_THAT(vox_error(placed_at({"-1000000 -1000000 -1000000", "1000000 1000000 1000000"})),
               Catch::Contains("2000001 x 2000001 x 2000001 blocks exceeds the budget"));
}

TEST_CASE(".vox hostile: instance and placed-voxel budgets", "[vox]") {
    // One group listing the same transform -> shape kMaxVoxInstances times loads; once more is refused.
    auto copies = [](const std::string& models, std::size_t n) {
        return vox_file(models + ntrn(0, 1) + ngrp(1, std::vector<int>(n, 2)) + ntrn(2, 3) + nshp(3, 0));
    };
    const VoxelScene many = parse_vox(copies(kCube, kMaxVoxInstances), kName);
    CHECK(many.solid_count() == 1);
    CHECK_THAT(vox_error(copies(kCube, kMaxVoxInstances + 1)),
               Catch::Contains("read hostile.vox: more than 65536 model instances in the scene graph"));
    // A 256 x 256 x 1 model of 65536 voxels placed 1025 times: 2^26 + 2^16 voxels to place, over the budget.
    std::vector<std::array<int, 4>> layer;
    for (int y = 0; y < 256; ++y)
        for (int x = 0; x < 256; ++x) layer.push_back({x, y, 0, 1});
    const std::string big = size_chunk(256, 256, 1) + xyzi(layer);
    double t = 0.0;
    CHECK_THAT(vox_error(copies(big, 1025), &t), Catch::Contains("more than 67108864 voxels placed"));
    CHECK(t < 1.0);
    // Within the budget, placing is O(1) per voxel: 2^24 placements (the probe's worst files took ~15 s of CPU
    // under the sanitizers when each voxel went through the full transform twice).
    const std::clock_t t0 = std::clock();
    const VoxelScene s = parse_vox(copies(big, 256), kName);
    CHECK(double(std::clock() - t0) / CLOCKS_PER_SEC < 2.0);
    CHECK(s.size == glm::ivec3(256, 1, 256));
    CHECK(s.solid_count() == 65536);
}

TEST_CASE(".vox hostile: counts beyond the bytes left are refused before allocating", "[vox]") {
    const int huge = 0x40000000;
    CHECK_THAT(vox_error(vox_file(size_chunk(2, 2, 2) + chunk("XYZI", i32(huge) + "abcd"))),
               Catch::Contains("truncated XYZI (1073741824 voxels declared)"));
    CHECK_THAT(vox_error(vox_file(kCube + chunk("nGRP", i32(0) + dict({}) + i32(huge) + i32(1)))),
               Catch::Contains("bad child count in nGRP"));
    CHECK_THAT(vox_error(vox_file(kCube + chunk("nSHP", i32(0) + dict({}) + i32(huge) + i32(0) + dict({})))),
               Catch::Contains("bad model count in nSHP"));
    CHECK_THAT(vox_error(vox_file(kCube + chunk("nTRN", i32(0) + i32(0x7fffffff) + std::string(16, '\0')))),
               Catch::Contains("bad dictionary size in nTRN"));
    CHECK_THAT(vox_error(vox_file(kCube + chunk("nTRN", i32(0) + i32(1) + i32(huge) + "_t" + std::string(8, '\0')))),
               Catch::Contains("truncated nTRN"));
    CHECK_THAT(vox_error(vox_file(kCube + chunk("MATL", i32(1) + i32(1) + i32(-5) + std::string(8, '\0')))),
               Catch::Contains("negative string length in MATL"));
}

TEST_CASE("a .vox nTRN frame count beyond its bytes is refused", "[vox]") {
    // nTRN: id, attributes, child, reserved, layer, frame count, frames (a dictionary each; only frame 0 is read).
    auto ntrn_frames = [](int frames) {
        return chunk("nTRN", i32(0) + dict({}) + i32(1) + i32(-1) + i32(-1) + i32(frames) + dict({}));
    };
    const std::string model = size_chunk(1, 1, 1) + xyzi({{0, 0, 0, 1}});
    const std::string shape = nshp(1, 0);
    CHECK_THROWS_WITH(ngi::parse_vox(vox_file(model + ntrn_frames(INT_MAX) + shape), "frames.vox"),
                      Contains("frames.vox") && Contains("nTRN declares 2147483647 frames"));
    CHECK(ngi::parse_vox(vox_file(model + ntrn_frames(1) + shape), "frames.vox").solid_count() == 1);
}

TEST_CASE(".vox hostile: MATL numbers must be finite", "[vox]") {
    auto matl = [](const std::string& key, const std::string& value) {
        return vox_file(kCube + chunk("MATL", i32(1) + dict({{"_type", "_emit"}, {key, value}})));
    };
    for (const char* v : {"inf", "nan", "1e39", "-inf", "", "0.5x"}) {
        INFO("'" << v << "'");
        CHECK_THAT(vox_error(matl("_emit", v)), Catch::Contains("bad number '") && Catch::Contains("in MATL _emit"));
        CHECK_THAT(vox_error(matl("_flux", v)), Catch::Contains("in MATL _flux"));
    }
    const VoxelScene s = parse_vox(matl("_emit", "0.5"), kName);
    REQUIRE(s.solid_count() == 1);
    CHECK(s.palette[s.at({0, 0, 0})].emission.r > 0.0f);
}

TEST_CASE(".vox emission that overflows after the flux scaling is refused", "[vox][render]") {
    const std::string cube = size_chunk(1, 1, 1) + xyzi({{0, 0, 0, 7}});
    auto matl = [&](const Dict& d) { return vox_file(cube + chunk("MATL", i32(7) + dict(d))); };
    auto error = [](const std::string& bytes) -> std::string {
        try {
            ngi::parse_vox(bytes, "lamp.vox");
        } catch (const ngi::InputError& e) {
            return e.what();
        }
        return "";
    };
    // Finite in the file, Inf after x 4 x 2^flux in float: the light then lit nothing and the reference was black.
    for (const Dict& d : {Dict{{"_type", "_emit"}, {"_emit", "3e38"}},
                          Dict{{"_type", "_emit"}, {"_emit", "1e37"}, {"_flux", "4"}},
                          Dict{{"_type", "_emit"}, {"_emit", "1100"}, {"_flux", "4"}}}) {  // 70,400 > 65,504
        INFO(d[1].second);
        CHECK_THAT(error(matl(d)), Contains("lamp.vox") && Contains("colour index 7") && Contains("exceeds the bound"));
    }
    // At the bound's edge: 1000 x 4 x 2^4 = 64,000 is accepted.
    const ngi::VoxelScene s = ngi::parse_vox(matl({{"_type", "_emit"}, {"_emit", "1000"}, {"_flux", "4"}}), "lamp.vox");
    CHECK(s.palette[s.at({0, 0, 0})].emission.r <= ngi::kMaxEmission);
    CHECK(s.palette[s.at({0, 0, 0})].emission.r > 1000.0f);

    // Every loader's materials pass through add_material, which holds the bound (procedural, meshes, API callers).
    ngi::VoxelScene api({2, 2, 2}, "api scene");
    CHECK_THROWS_WITH(api.add_material({glm::vec3(0.5f), glm::vec3(1e30f), false}),
                      Contains("api scene") && Contains("material 1") && Contains("emission"));
    CHECK_THROWS_AS(api.add_material({glm::vec3(0.5f), glm::vec3(std::nanf("")), false}), ngi::InputError);
    CHECK_THROWS_AS(api.add_material({glm::vec3(0.5f), glm::vec3(-1.0f), false}), ngi::InputError);
    CHECK(api.add_material({glm::vec3(0.5f), glm::vec3(ngi::kMaxEmission), false}) == 1);

    // A mesh's emission (OBJ Ke) meets the same bound, naming the file.
    ngi::test::TempDir dir("vox-emission");
    ngi::test::spit(dir / "hot.obj", "mtllib hot.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl hot\nf 1 2 3\n");
    ngi::test::spit(dir / "hot.mtl", "newmtl hot\nKd 1 1 1\nKe 1e30 1e30 1e30\n");
    CHECK_THROWS_WITH(ngi::make_scene(dir / "hot.obj"), Contains("hot.obj") && Contains("emission"));

    // The area light too.
    ngi::AreaLight l;
    l.centre = {1, 2, 3};
    l.half_u = {1, 0, 0};
    l.half_v = {0, 0, 1};
    l.radiance = {1e5f, 1, 1};
    CHECK_THROWS_WITH(ngi::check_area_light(l, "--area-light"), Contains("--area-light") && Contains("emission bound"));
    l.radiance = {60, 56, 50};
    CHECK_NOTHROW(ngi::check_area_light(l, "--area-light"));
}

TEST_CASE(".vox: load_vox(path) is parse_vox of the file's bytes", "[vox]") {
    const std::string bytes = vox_file(size_chunk(3, 2, 4) + xyzi({{0, 0, 0, 1}, {2, 1, 3, 5}, {1, 0, 2, 200}}) +
                                       ntrn(0, 1) + ngrp(1, {2}) + ntrn(2, 3, {{"_t", "10 -4 7"}, {"_r", "17"}}) +
                                       nshp(3, 0));
    const auto dir = std::filesystem::temp_directory_path() / "ngi_render_tests";
    std::filesystem::create_directories(dir);
    const std::string path = (dir / "same.vox").string();
    std::ofstream(path, std::ios::binary) << bytes;
    const VoxelScene a = load_vox(path), b = parse_vox(bytes, path);
    CHECK(a.name == path);
    CHECK(b.name == path);
    CHECK(a.size == b.size);
    CHECK(a.voxels == b.voxels);
    CHECK(a.palette.size() == b.palette.size());
    CHECK(a.solid_count() == 3);
}

// Issue 31, item 6: a valid 14 KB scene padded to a 3 GiB sparse .vox was read whole (38 s, 4 GB RSS, exit 0).
TEST_CASE("a .vox file beyond kMaxVoxFileBytes is refused before it is read", "[vox][limits]") {
    ngi::test::TempDir dir("vox-size");
    const fs::path path = dir / "padded.vox";
    ngi::test::spit(path, vox_file(size_chunk(1, 1, 1) + xyzi({{0, 0, 0, 7}})));
    CHECK(ngi::load_vox(path.string()).palette.size() > 1);  // valid as written
    fs::resize_file(path, ngi::kMaxVoxFileBytes + 1);           // sparse: no disk space, no memory
    // Refused from the size fstat reports (the message quotes it), before any byte is read.
    CHECK_THROWS_WITH(ngi::load_vox(path.string()),
                      Contains("padded.vox") && Contains("is larger (" + std::to_string(ngi::kMaxVoxFileBytes + 1)));
}

TEST_CASE(".vox: the fuzzer's seed files are valid scenes", "[vox]") {
    // fuzz/corpus/vox/ holds the seeds fuzz/make_vox_seeds.py writes (and, beside them, inputs that once found bugs).
    for (const char* name : {"single.vox", "palette_emit.vox", "graph.vox", "shared_skipped.vox", "v200_frames.vox"}) {
        INFO(name);
        const VoxelScene s = load_vox(std::string(NGI_SOURCE_DIR) + "/fuzz/corpus/vox/" + name);
        CHECK(s.solid_count() > 0);
    }
}

TEST_CASE(".vox: every file of the fuzz corpus loads or is refused cleanly, quickly", "[vox]") {
    // The corpus also keeps inputs the fuzzer found trouble with (slow_*.vox: a mutated doubling graph that took
    // 10 s under the sanitizers before placement became O(1) per voxel). Each must end in a scene or an InputError.
    int files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(std::string(NGI_SOURCE_DIR) + "/fuzz/corpus/vox")) {
        std::ifstream in(entry.path(), std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        INFO(entry.path().string());
        double t = 0.0;
        const std::string e = vox_error(bytes, &t);
        CHECK((e.empty() || e.find("read hostile.vox: ") == 0));
        CHECK(t < 1.0);
        ++files;
    }
    CHECK(files >= 8);
}
