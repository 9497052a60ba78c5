// Voxel scenes: procedural families, scene specs, and MagicaVoxel .vox files (valid, and broken ones).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "ngi/error.hpp"
#include "ngi/scene.hpp"
#include "vox_writer.hpp"

using namespace ngi;
using namespace vox_test;

namespace {

std::string tmp_path(const std::string& name) {
    const auto dir = std::filesystem::temp_directory_path() / "ngi_render_tests";
    std::filesystem::create_directories(dir);
    return (dir / name).string();
}
std::string write(const std::string& name, const std::string& bytes) {
    const std::string p = tmp_path(name);
    std::ofstream(p, std::ios::binary) << bytes;
    return p;
}

float srgb(int v) {
    const float c = float(v) / 255.0f;
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

// The InputError message of load_vox, or "" if it loaded.
std::string vox_error(const std::string& path) {
    try {
        load_vox(path);
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST_CASE("procedural families: deterministic per seed, distinct, lit as described", "[render]") {
    REQUIRE(scene_families() == std::vector<std::string>{"room", "street", "cave", "backlit", "bleed", "sculpture",
                                                         "cornell", "cornell_pink", "knot", "superquadric", "blob"});
    for (const auto& fam : scene_families()) {
        INFO(fam);
        if (fam == "knot" || fam == "superquadric" || fam == "blob") continue;  // triangles, no blocks: test_mesh.cpp
        const VoxelScene a = generate_scene(fam, 3), b = generate_scene(fam, 3), c = generate_scene(fam, 4);
        CHECK(a.name == fam + ":seed=3");
        CHECK(a.voxels == b.voxels);
        CHECK(a.palette.size() == b.palette.size());
        CHECK((a.voxels != c.voxels || a.size != c.size));
        CHECK(a.solid_count() > 100);
        CHECK(a.solid_count() < a.voxels.size());
        for (auto v : a.voxels) REQUIRE(v < a.palette.size());
        bool lamp = false, emitter = false;
        for (std::size_t i = 1; i < a.palette.size(); ++i) {
            lamp |= a.palette[i].lamp;
            emitter |= a.palette[i].emission != glm::vec3(0.0f) && !a.palette[i].lamp;
        }
        if (fam == "room" || fam == "street" || fam == "bleed") CHECK(lamp);
        if (fam == "backlit") CHECK_FALSE(lamp);  // lit only through its opening
        if (fam == "cave" || fam == "cornell" || fam == "cornell_pink") CHECK(emitter);
        if (fam == "cornell" || fam == "cornell_pink") CHECK(a.size == glm::ivec3(40));  // one grid for the family
    }
}

TEST_CASE("cornell_pink is cornell of the same seed with a pink back wall and one more box", "[render]") {
    const VoxelScene a = generate_scene("cornell", 5), b = generate_scene("cornell_pink", 5);
    REQUIRE(a.size == b.size);
    const glm::vec3 back_a = a.palette[a.at({20, 20, 0})].albedo, back_b = b.palette[b.at({20, 20, 0})].albedo;
    CHECK(std::abs(back_a.r - back_a.b) < 0.1f);  // white
    CHECK(back_b.r > back_b.g + 0.2f);                       // pink
    std::size_t only_b = 0;
    for (std::size_t i = 0; i < a.voxels.size(); ++i) {
        REQUIRE((a.voxels[i] == 0 || b.voxels[i] != 0));  // everything of cornell is there
        only_b += a.voxels[i] == 0 && b.voxels[i] != 0;
    }
    CHECK(only_b >= 4 * 4 * 4 / 2);  // the extra box (at least 4^3 blocks, perhaps partly inside another)
}

TEST_CASE("scene specs", "[render]") {
    CHECK(make_scene("room:seed=7").voxels == generate_scene("room", 7).voxels);
    CHECK(make_scene("cave").name == "cave:seed=0");
    CHECK(scene_spec_name("bleed") == "bleed:seed=0");
    CHECK(scene_spec_name("x/y.VOX") == "x/y.VOX");
    CHECK_THROWS_WITH(make_scene("forest:seed=1"), Catch::Contains("unknown family 'forest'"));
    CHECK_THROWS_WITH(make_scene("room:seed=abc"), Catch::Contains("seed must be"));
    CHECK_THROWS_WITH(make_scene("room:size=3"), Catch::Contains("unknown option 'size'"));
    CHECK_THROWS_AS(make_scene("room:seed=-1"), InputError);
}

TEST_CASE(".vox: models, palette, scene graph and unknown chunks", "[render][vox]") {
    // One 3x2x4 model (MagicaVoxel z up) with three voxels, a custom palette and an emissive material, plus the
    // chunks MagicaVoxel writes that we do not use.
    std::string rgba;
    for (int i = 0; i < 256; ++i) rgba += std::string{char(i), char(255 - i), char(i / 2), char(255)};
    const std::string file = vox_file(
        chunk("PACK", i32(1)) + size_chunk(3, 2, 4) + xyzi({{0, 0, 0, 1}, {2, 1, 3, 5}, {1, 0, 2, 200}}) +
        chunk("nTRN", i32(0) + dict({}) + i32(1) + i32(-1) + i32(0) + i32(1) + dict({})) +
        chunk("nGRP", i32(1) + dict({}) + i32(1) + i32(2)) +
        chunk("nTRN", i32(2) + dict({{"_name", "m"}}) + i32(3) + i32(-1) + i32(0) + i32(1) + dict({{"_t", "10 -4 7"}})) +
        chunk("nSHP", i32(3) + dict({}) + i32(1) + i32(0) + dict({})) +
        chunk("LAYR", i32(0) + dict({{"_name", "layer"}}) + i32(-1)) + chunk("RGBA", rgba) +
        chunk("MATL", i32(5) + dict({{"_type", "_emit"}, {"_emit", "0.5"}, {"_flux", "1"}})) +
        chunk("rOBJ", dict({{"_type", "_bg"}})) + chunk("rCAM", i32(0) + dict({})) + chunk("NOTE", i32(0)) +
        chunk("IMAP", std::string(256, '\0')) + chunk("ZZZZ", "whatever", chunk("YYYY", "nested")));
    const std::string path = write("good.vox", file);
    const VoxelScene s = load_vox(path);
    CHECK(s.name == path);
    // The bounding box of the voxels: x 0..2, y 0..1, z 0..3 (vox) -> 3 x 4 x 2 blocks (ours: x, z, -y).
    REQUIRE(s.size == glm::ivec3(3, 4, 2));
    CHECK(s.solid_count() == 3);
    // vox (x, y, z) -> ours (x, z, 1 - y)
    const glm::ivec3 cells[3] = {{0, 0, 1}, {2, 3, 0}, {1, 2, 1}};
    const int colour[3] = {1, 5, 200};
    for (int k = 0; k < 3; ++k) {
        const std::uint8_t m = s.at(cells[k]);
        REQUIRE(m != 0);
        const int i = colour[k] - 1;  // RGBA entry i is colour index i + 1
        const glm::vec3 albedo(srgb(i), srgb(255 - i), srgb(i / 2));
        CHECK(s.palette[m].albedo.r == Approx(std::min(albedo.r, 0.95f)));
        CHECK(s.palette[m].albedo.g == Approx(std::min(albedo.g, 0.95f)));
        CHECK(s.palette[m].albedo.b == Approx(std::min(albedo.b, 0.95f)));
        CHECK((s.palette[m].emission != glm::vec3(0.0f)) == (colour[k] == 5));
    }

    // Two models placed by the scene graph (translation + a 90-degree rotation), default palette.
    const std::string two = vox_file(
        size_chunk(2, 1, 1) + xyzi({{0, 0, 0, 1}, {1, 0, 0, 1}}) + size_chunk(1, 1, 1) + xyzi({{0, 0, 0, 2}}) +
        chunk("nTRN", i32(0) + dict({}) + i32(1) + i32(-1) + i32(-1) + i32(1) + dict({})) +
        chunk("nGRP", i32(1) + dict({}) + i32(2) + i32(2) + i32(4)) +
        // rotation byte: row 0 -> column 1, row 1 -> column 0 (a z rotation), no sign flips
        chunk("nTRN", i32(2) + dict({}) + i32(3) + i32(-1) + i32(0) + i32(1) + dict({{"_r", "1"}, {"_t", "0 0 0"}})) +
        chunk("nSHP", i32(3) + dict({}) + i32(1) + i32(0) + dict({})) +
        chunk("nTRN", i32(4) + dict({}) + i32(5) + i32(-1) + i32(0) + i32(1) + dict({{"_t", "5 0 2"}})) +
        chunk("nSHP", i32(5) + dict({}) + i32(1) + i32(1) + dict({})));
    const VoxelScene t = load_vox(write("two.vox", two));
    CHECK(t.solid_count() == 3);
    // Model 0 turned to lie along vox y (2 cells), model 1 at (5, 0, 2): extent x 0..5, y -1..0, z 0..2.
    CHECK(t.size == glm::ivec3(6, 3, 2));
    const std::uint8_t white = t.at({5, 2, 0});  // model 1 at vox (5, 0, 2) -> ours (5, 2, 0) after the shift
    REQUIRE(white != 0);
    CHECK(t.palette[white].albedo.r == Approx(0.95f));  // default palette index 2: r ff, g ff, b cc
    CHECK(t.palette[white].albedo.g == Approx(0.95f));
    CHECK(t.palette[white].albedo.b == Approx(srgb(0xcc)));
}

TEST_CASE(".vox: broken files give errors that name the file", "[render][vox]") {
    const std::string good = vox_file(size_chunk(2, 2, 2) + xyzi({{0, 0, 0, 1}, {1, 1, 1, 2}}));
    REQUIRE(vox_error(write("ok.vox", good)).empty());

    SECTION("truncated anywhere") {
        for (std::size_t cut : {std::size_t(3), std::size_t(8), std::size_t(14), std::size_t(30), good.size() - 1}) {
            const std::string p = write("cut.vox", good.substr(0, cut));
            const std::string e = vox_error(p);
            INFO("cut at " << cut << ": " << e);
            CHECK(e.find(p) != std::string::npos);
            CHECK((e.find("truncated") != std::string::npos || e.find("not a MagicaVoxel") != std::string::npos));
        }
        const std::string p = write("short_xyzi.vox", vox_file(size_chunk(2, 2, 2) + chunk("XYZI", i32(5) + "abcd")));
        CHECK_THAT(vox_error(p), Catch::Contains(p) && Catch::Contains("truncated XYZI"));
    }
    SECTION("malformed chunk structure") {
        std::string bad_id = good;
        bad_id[20] = '\x01';  // first child chunk's id ("SIZE") becomes binary garbage
        std::string p = write("bad_id.vox", bad_id);
        CHECK_THAT(vox_error(p), Catch::Contains(p) && Catch::Contains("malformed chunk structure"));
        p = write("neg.vox", "VOX " + i32(150) + "MAIN" + i32(0) + i32(-12));
        CHECK_THAT(vox_error(p), Catch::Contains(p) && Catch::Contains("negative size"));
        p = write("no_main.vox", "VOX " + i32(150) + chunk("SIZE", i32(1) + i32(1) + i32(1)));
        CHECK_THAT(vox_error(p), Catch::Contains(p) && Catch::Contains("expected MAIN"));
        p = write("xyzi_first.vox", vox_file(xyzi({{0, 0, 0, 1}})));
        CHECK_THAT(vox_error(p), Catch::Contains(p) && Catch::Contains("XYZI without SIZE"));
        // A child whose declared size runs past its parent.
        p = write("overrun.vox", "VOX " + i32(150) + "MAIN" + i32(0) + i32(16) + "SIZE" + i32(100) + i32(0) + i32(2));
        CHECK_THAT(vox_error(p), Catch::Contains(p) && Catch::Contains("truncated chunk 'SIZE'"));
        p = write("header.vox", "RIFF" + i32(150));
        CHECK_THAT(vox_error(p), Catch::Contains(p) && Catch::Contains("not a MagicaVoxel file"));
        p = write("outside.vox", vox_file(size_chunk(2, 2, 2) + xyzi({{0, 2, 0, 1}})));
        CHECK_THAT(vox_error(p), Catch::Contains(p) && Catch::Contains("outside its model"));
        p = write("cycle.vox", vox_file(size_chunk(1, 1, 1) + xyzi({{0, 0, 0, 1}}) +
                                        chunk("nTRN", i32(0) + dict({}) + i32(1) + i32(-1) + i32(0) + i32(1) + dict({})) +
                                        chunk("nGRP", i32(1) + dict({}) + i32(1) + i32(0))));
        CHECK_THAT(vox_error(p), Catch::Contains(p) && Catch::Contains("cycle"));
        CHECK_THAT(vox_error(tmp_path("does_not_exist.vox")), Catch::Contains("cannot open"));
    }
    SECTION("absurd dimensions") {
        std::string p = write("huge.vox", vox_file(size_chunk(300, 10, 10) + xyzi({{0, 0, 0, 1}})));
        CHECK_THAT(vox_error(p), Catch::Contains(p) && Catch::Contains("outside 1..256 per axis"));
        p = write("zero.vox", vox_file(size_chunk(0, 10, 10)));
        CHECK_THAT(vox_error(p), Catch::Contains(p) && Catch::Contains("outside 1..256"));
        // Each model is small, but the scene graph spreads them over a box far beyond the block budget.
        const std::string far = vox_file(
            size_chunk(1, 1, 1) + xyzi({{0, 0, 0, 1}}) +
            chunk("nTRN", i32(0) + dict({}) + i32(1) + i32(-1) + i32(-1) + i32(1) + dict({})) +
            chunk("nGRP", i32(1) + dict({}) + i32(2) + i32(2) + i32(4)) +
            chunk("nTRN", i32(2) + dict({}) + i32(3) + i32(-1) + i32(0) + i32(1) + dict({{"_t", "-2000 -2000 -2000"}})) +
            chunk("nSHP", i32(3) + dict({}) + i32(1) + i32(0) + dict({})) +
            chunk("nTRN", i32(4) + dict({}) + i32(3) + i32(-1) + i32(0) + i32(1) + dict({{"_t", "2000 2000 2000"}})));
        p = write("far.vox", far);
        CHECK_THAT(vox_error(p), Catch::Contains(p) && Catch::Contains("exceeds the budget"));
    }
}
