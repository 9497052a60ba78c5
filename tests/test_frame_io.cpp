// The frame folder: write_frame -> read_frame round trip, safe replacement, no partial folder after a failing
// write, and every kind of bad input read_frame must name: missing files, sizes, channels, NaN/Inf, depth.
#include <catch2/catch.hpp>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <random>

#include "io_test_support.hpp"
#include "ngi/error.hpp"
#include "ngi/image_io.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using ngi::test::TempDir;

namespace {

ngi::Frame make_frame(int n, std::mt19937& rng, bool with_reference = true) {
    ngi::Frame f;
    f.n = n;
    f.look = {0.3f, -0.2f, -1.0f};
    f.up = {0.0f, 1.0f, 0.1f};
    std::uniform_real_distribution<float> u(0.0f, 1.0f), hdr(0.0f, 50.0f), depth(0.1f, 20000.0f);
    for (int fi = 0; fi < ngi::kFeatureCount; ++fi)
        for (int k = 0; k < ngi::kFaceCount; ++k) {
            const auto feature = ngi::Feature(fi);
            ngi::Image img(n, n, ngi::feature_channels(feature));
            for (float& v : img.data)
                v = feature == ngi::Feature::Depth    ? depth(rng)
                    : feature == ngi::Feature::Albedo ? u(rng)
                    : feature == ngi::Feature::Normal ? 2.0f * u(rng) - 1.0f
                                                      : hdr(rng);
            f.get(feature, ngi::Face(k)) = std::move(img);
        }
    if (with_reference) {
        f.reference = ngi::Image(n, n, 3);
        for (float& v : f.reference->data) v = hdr(rng);
    }
    return f;
}

std::string file_of(ngi::Feature f, ngi::Face face, const char* ext = ".exr") {
    return std::string(ngi::face_name(face)) + "_" + ngi::feature_name(f) + ext;
}

// Leftovers of write_frame next to the target (<dir>.tmp-*, <dir>.old*).
std::vector<std::string> siblings(const TempDir& root) { return root.list(); }

}  // namespace

TEST_CASE("frame folder: write_frame -> read_frame round trip", "[io][frame]") {
    TempDir root("frame-rt");
    std::mt19937 rng(1);
    const ngi::Frame f = make_frame(16, rng);
    const std::string dir = root / "train/frame0";
    ngi::write_frame(dir + "/", f);  // a trailing slash names the same folder; missing parents are created
    CHECK(siblings(root) == std::vector<std::string>{"train"});
    CHECK(fs::is_regular_file(dir + "/camera.json"));

    ngi::FrameReadStats stats;
    const ngi::Frame r = ngi::read_frame(dir, &stats);
    CHECK(stats.total_sanitized() == 0);
    CHECK(stats.sanitized.empty());
    CHECK(stats.ldr_files.empty());
    CHECK(r.n == 16);
    CHECK(r.look == f.look);
    CHECK(r.up == f.up);
    for (int fi = 0; fi < ngi::kFeatureCount; ++fi)
        for (int k = 0; k < ngi::kFaceCount; ++k) {
            const auto feature = ngi::Feature(fi);
            const ngi::Image &a = f.get(feature, ngi::Face(k)), &b = r.get(feature, ngi::Face(k));
            INFO(file_of(feature, ngi::Face(k)));
            REQUIRE(b.channels == a.channels);
            REQUIRE(b.width == 16);
            if (feature == ngi::Feature::Depth || feature == ngi::Feature::Normal) {
                CHECK(b.data == a.data);  // float: exact, also for depths of 20 km
            } else {
                CHECK(ngi::test::worst_ratio(b.data, a.data, 1e-6, std::ldexp(1.0, -11)) <= 1.0);  // half
            }
        }
    REQUIRE(r.reference);
    CHECK(r.reference->data == f.reference->data);
}

TEST_CASE("frame folder: a colour value beyond the half range is written as float, not clamped", "[io][frame]") {
    TempDir root("frame-bright");
    std::mt19937 rng(2);
    ngi::Frame f = make_frame(8, rng, false);
    f.get(ngi::Feature::Emission, ngi::Face::Up).data[3] = 1.5e5f;  // the sun
    ngi::write_frame(root / "f", f);
    const ngi::Frame r = ngi::read_frame(root / "f");
    CHECK(r.get(ngi::Feature::Emission, ngi::Face::Up).data == f.get(ngi::Feature::Emission, ngi::Face::Up).data);
    CHECK_FALSE(r.reference);
}

TEST_CASE("frame folder: a reference of another size than the faces is refused, naming both sizes", "[io][frame]") {
    TempDir root("frame-refsize");
    std::mt19937 rng(5);
    ngi::Frame f = make_frame(8, rng);
    ngi::write_frame(root / "f", f);
    ngi::write_exr(root / "f/reference.exr", ngi::Image(16, 8, 3), ngi::ExrPixelType::Float);
    CHECK_THROWS_WITH(ngi::read_frame(root / "f"),
                      Contains("reference.exr") && Contains("16x8") && Contains("8x8") && Contains("face size"));
    f.reference = ngi::Image(4, 4, 3);  // and write_frame does not write such a frame
    CHECK_THROWS_WITH(ngi::write_frame(root / "g", f), Contains("reference") && Contains("8x8x3"));
    CHECK_FALSE(fs::exists(root / "g"));
}

TEST_CASE("frame folder: emission and env are optional, on all faces or none", "[io][frame]") {
    TempDir root("frame-optional");
    std::mt19937 rng(6);
    ngi::Frame f = make_frame(8, rng, false);
    for (auto& img : f.faces[int(ngi::Feature::Env)]) img = ngi::Image();
    ngi::write_frame(root / "f", f);
    CHECK_FALSE(fs::exists(root / "f/front_env.exr"));
    CHECK(fs::exists(root / "f/front_emission.exr"));
    const ngi::Frame r = ngi::read_frame(root / "f");
    for (int k = 0; k < ngi::kFaceCount; ++k) {
        CHECK(r.get(ngi::Feature::Env, ngi::Face(k)).width == 0);
        CHECK(r.get(ngi::Feature::Env, ngi::Face(k)).data.empty());
        CHECK(r.get(ngi::Feature::Emission, ngi::Face(k)).width == 8);
    }
    // Present on some faces only: refused on write, and on read the missing file is named.
    f.get(ngi::Feature::Env, ngi::Face::Up) = ngi::Image(8, 8, 3);
    CHECK_THROWS_WITH(ngi::write_frame(root / "g", f), Contains("front env"));
    fs::remove(root / "f/down_emission.exr");
    CHECK_THROWS_WITH(ngi::read_frame(root / "f"), Contains("down_emission.exr") && Contains("optional"));
}

TEST_CASE("frame folder: replacing, refusing, and never leaving a partial folder", "[io][frame]") {
    TempDir root("frame-safe");
    std::mt19937 rng(3);
    const ngi::Frame f1 = make_frame(8, rng), f2 = make_frame(8, rng, false);
    const std::string dir = root / "frame";

    ngi::write_frame(dir, f1);
    ngi::write_frame(dir, f2);  // replaces a frame folder, reference.exr of the old one included
    CHECK_FALSE(fs::exists(dir + "/reference.exr"));
    CHECK(ngi::read_frame(dir).get(ngi::Feature::Depth, ngi::Face::Back).data ==
          f2.get(ngi::Feature::Depth, ngi::Face::Back).data);
    CHECK(siblings(root) == std::vector<std::string>{"frame"});

    // A non-empty folder that is not a frame folder is never replaced.
    fs::create_directories(root / "home");
    ngi::test::spit(root / "home/thesis.tex", "precious");
    CHECK_THROWS_WITH(ngi::write_frame(root / "home", f1), Contains("not a frame folder"));
    CHECK(ngi::test::slurp(root / "home/thesis.tex") == "precious");
    ngi::test::spit(root / "file", "x");
    CHECK_THROWS_WITH(ngi::write_frame(root / "file", f1), Contains("not a directory"));

    // An invalid frame is refused before anything is written.
    ngi::Frame bad = f1;
    bad.get(ngi::Feature::Normal, ngi::Face::Left) = ngi::Image(8, 8, 1);
    CHECK_THROWS_WITH(ngi::write_frame(root / "new", bad), Contains("left normal") && Contains("8x8x3"));
    bad = f1;
    bad.get(ngi::Feature::Env, ngi::Face::Down) = ngi::Image(8, 7, 3);
    CHECK_THROWS_WITH(ngi::write_frame(root / "new", bad), Contains("down env"));
    bad = f1;
    bad.look = {0, 0, 0};
    CHECK_THROWS_WITH(ngi::write_frame(root / "new", bad), Contains("look"));

    // The disk fills up in the middle: neither <dir> nor a temporary folder remains, and an existing frame stays.
    {
        ngi::test::FileSizeLimit limit(16 * 1024);
        const ngi::Frame big = make_frame(96, rng);  // float normal faces alone are ~110 KB each
        CHECK_THROWS_AS(ngi::write_frame(root / "new", big), ngi::InputError);
        CHECK_THROWS_AS(ngi::write_frame(dir, big), ngi::InputError);
    }
    CHECK(siblings(root) == std::vector<std::string>{"file", "frame", "home"});
    CHECK(ngi::read_frame(dir).get(ngi::Feature::Depth, ngi::Face::Back).data ==
          f2.get(ngi::Feature::Depth, ngi::Face::Back).data);
}

TEST_CASE("frame folder: bad input is an InputError naming the file", "[io][frame]") {
    TempDir root("frame-bad");
    std::mt19937 rng(4);
    const ngi::Frame f = make_frame(8, rng);
    const std::string dir = root / "f";
    auto fresh = [&] { ngi::write_frame(dir, f); };
    auto path = [&](const std::string& name) { return dir + "/" + name; };

    fresh();
    fs::remove(path("left_depth.exr"));
    CHECK_THROWS_WITH(ngi::read_frame(dir), Contains("missing") && Contains("left_depth.exr"));

    fresh();
    fs::remove(path("up_albedo.exr"));
    CHECK_THROWS_WITH(ngi::read_frame(dir), Contains("up_albedo.exr (or .png)"));

    fresh();
    fs::remove(path("camera.json"));
    CHECK_THROWS_WITH(ngi::read_frame(dir), Contains("camera.json") && Contains("cannot open"));
    ngi::test::spit(path("camera.json"), "{\"look\": [0, 0, -1]}");
    CHECK_THROWS_WITH(ngi::read_frame(dir), Contains("camera.json") && Contains("\"up\""));
    ngi::test::spit(path("camera.json"), "{\"look\": [0, 0, -1], \"up\": [0, 0, 2]}");
    CHECK_THROWS_WITH(ngi::read_frame(dir), Contains("camera.json") && Contains("parallel"));
    ngi::test::spit(path("camera.json"), "{\"look\": [0, 0, -1], ");
    CHECK_THROWS_WITH(ngi::read_frame(dir), Contains("camera.json") && Contains("not valid JSON"));
    CHECK_THROWS_WITH(ngi::read_frame(root / "nope"), Contains("nope") && Contains("not a directory"));

    fresh();  // faces of different sizes
    ngi::write_exr(path("right_normal.exr"), ngi::Image(9, 9, 3), ngi::ExrPixelType::Float);
    CHECK_THROWS_WITH(ngi::read_frame(dir), Contains("right_normal.exr") && Contains("9x9") && Contains("8x8") &&
                                                Contains("front_albedo.exr"));

    fresh();  // non-square
    ngi::write_exr(path("front_albedo.exr"), ngi::Image(8, 6, 3));
    CHECK_THROWS_WITH(ngi::read_frame(dir), Contains("front_albedo.exr") && Contains("8x6") && Contains("square"));

    fresh();  // wrong channel counts
    ngi::write_exr(path("back_direct.exr"), ngi::Image(8, 8, 1));
    CHECK_THROWS_WITH(ngi::read_frame(dir), Contains("back_direct.exr") && Contains("1 channel(s), expected 3"));
    fresh();
    ngi::write_exr(path("back_depth.exr"), ngi::Image(8, 8, 3), ngi::ExrPixelType::Float);
    CHECK_THROWS_WITH(ngi::read_frame(dir), Contains("back_depth.exr") && Contains("expected 1"));
    fresh();
    ngi::write_exr(path("back_env.exr"), ngi::Image(8, 8, 5));
    CHECK_THROWS_WITH(ngi::read_frame(dir), Contains("back_env.exr") && Contains("5 channel(s)"));

    fresh();  // negative depth: an error naming the file and how many pixels
    ngi::Image d = f.get(ngi::Feature::Depth, ngi::Face::Down);
    d.data[0] = -1.0f;
    d.data[5] = -std::numeric_limits<float>::infinity();
    d.data[6] = -0.5f;
    ngi::write_exr(path("down_depth.exr"), d, ngi::ExrPixelType::Float);
    CHECK_THROWS_WITH(ngi::read_frame(dir), Contains("down_depth.exr") && Contains("3 of 64 pixels") &&
                                                Contains("negative depth"));

    fresh();  // a truncated face file
    const std::string bytes = ngi::test::slurp(path("front_env.exr"));
    ngi::test::spit(path("front_env.exr"), bytes.substr(0, bytes.size() / 2));
    CHECK_THROWS_WITH(ngi::read_frame(dir), Contains("front_env.exr"));

    fresh();  // both an .exr and a .png of one feature
    ngi::write_png(path("front_albedo.png"), ngi::Image(8, 8, 3));
    CHECK_THROWS_WITH(ngi::read_frame(dir), Contains("front_albedo.exr") && Contains("front_albedo.png"));
    // Normals as PNG are not accepted (signed values): the .png is not even looked at.
    fs::remove(path("front_albedo.png"));
    fs::rename(path("front_normal.exr"), path("front_normal.png"));
    CHECK_THROWS_WITH(ngi::read_frame(dir), Contains("missing") && Contains("front_normal.exr"));
}

TEST_CASE("frame folder: NaN/Inf are sanitized by feature and counted per file, PNG and RGBA features", "[io][frame]") {
    TempDir root("frame-nan");
    std::mt19937 rng(5);
    ngi::Frame f = make_frame(8, rng);
    const std::string dir = root / "f";
    ngi::write_frame(dir, f);
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    const float fmax = std::numeric_limits<float>::max();
    const std::size_t plane = 64;

    ngi::Image albedo_f = f.get(ngi::Feature::Albedo, ngi::Face::Front);
    albedo_f.data[0] = inf; albedo_f.data[1] = -inf; albedo_f.data[2] = nan;
    ngi::write_exr(dir + "/front_albedo.exr", albedo_f, ngi::ExrPixelType::Half);
    ngi::Image normal = f.get(ngi::Feature::Normal, ngi::Face::Front);
    normal.data[plane + 4] = nan;           // y of pixel 4
    normal.data[2 * plane + 9] = -inf;      // z of pixel 9
    ngi::write_exr(dir + "/front_normal.exr", normal, ngi::ExrPixelType::Float);
    ngi::Image depth = f.get(ngi::Feature::Depth, ngi::Face::Up);
    depth.data[0] = inf;
    depth.data[1] = nan;
    ngi::write_exr(dir + "/up_depth.exr", depth, ngi::ExrPixelType::Float);
    ngi::Image direct = f.get(ngi::Feature::Direct, ngi::Face::Left);
    direct.data[1] = nan; direct.data[2] = nan; direct.data[3] = nan; direct.data[10] = inf; direct.data[11] = -inf;
    ngi::write_exr(dir + "/left_direct.exr", direct, ngi::ExrPixelType::Half);
    ngi::Image ref = *f.reference;
    ref.data[7] = nan;
    ngi::write_exr(dir + "/reference.exr", ref, ngi::ExrPixelType::Float);

    // An albedo as 8-bit PNG (LDR) and an env map with an alpha channel.
    ngi::Image albedo = f.get(ngi::Feature::Albedo, ngi::Face::Back);
    fs::remove(dir + "/back_albedo.exr");
    ngi::write_png(dir + "/back_albedo.png", albedo);
    ngi::Image env = f.get(ngi::Feature::Env, ngi::Face::Right), env_rgba(8, 8, 4, 1.0f);
    std::copy(env.data.begin(), env.data.end(), env_rgba.data.begin());
    ngi::write_exr(dir + "/right_env.exr", env_rgba, ngi::ExrPixelType::Float);

    ngi::FrameReadStats stats;
    const ngi::Frame r = ngi::read_frame(dir, &stats);
    // Read order: features (albedo, normal, depth, direct, ...), faces within a feature, then the reference.
    REQUIRE(stats.sanitized.size() == 5);
    const std::pair<const char*, std::array<std::size_t, 2>> expected[] = {
        {"front_albedo.exr", {1, 2}}, {"front_normal.exr", {1, 1}}, {"up_depth.exr", {1, 1}},
        {"left_direct.exr", {3, 2}}, {"reference.exr", {1, 0}}};
    for (int i = 0; i < 5; ++i) {
        CHECK(stats.sanitized[i].file == expected[i].first);
        CHECK(stats.sanitized[i].nan == expected[i].second[0]);
        CHECK(stats.sanitized[i].inf == expected[i].second[1]);
    }
    CHECK(stats.total_sanitized() == 13);
    CHECK(stats.ldr_files == std::vector<std::string>{"back_albedo.png"});

    const auto& ra = r.get(ngi::Feature::Albedo, ngi::Face::Front).data;
    CHECK(ra[0] == 1.0f);
    CHECK(ra[1] == 0.0f);
    CHECK(ra[2] == 0.0f);
    const auto& rn = r.get(ngi::Feature::Normal, ngi::Face::Front).data;
    for (int p : {4, 9}) {  // the whole vector is zeroed, not just the bad component
        CHECK(rn[p] == 0.0f);
        CHECK(rn[plane + p] == 0.0f);
        CHECK(rn[2 * plane + p] == 0.0f);
    }
    CHECK(rn[5] == normal.data[5]);
    const auto& dd = r.get(ngi::Feature::Depth, ngi::Face::Up).data;
    CHECK(dd[0] == fmax);
    CHECK(dd[1] == fmax);
    const auto& rd = r.get(ngi::Feature::Direct, ngi::Face::Left).data;
    CHECK(rd[1] == 0.0f);
    CHECK(rd[10] == fmax);
    CHECK(rd[11] == 0.0f);
    CHECK(r.reference->data[7] == 0.0f);
    for (int fi = 0; fi < ngi::kFeatureCount; ++fi)
        for (int k = 0; k < ngi::kFaceCount; ++k) CHECK(ngi::test::all_finite(r.get(ngi::Feature(fi), ngi::Face(k)).data));
    CHECK(ngi::test::max_abs_diff(r.get(ngi::Feature::Albedo, ngi::Face::Back).data, albedo.data) <= 0.5 / 255 + 1e-7);
    CHECK(r.get(ngi::Feature::Env, ngi::Face::Right).data == env.data);  // alpha dropped
}
