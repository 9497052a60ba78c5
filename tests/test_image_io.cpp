// Image files: OpenEXR (half/float, 1..N channels), PNG (8-bit round trips; 16-bit and palette files from an
// independent hand-made encoder below), .npy, dispatch by extension, and bad input: missing, wrong-format and
// truncated files must give an InputError naming the file, and a failing write must leave nothing behind.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "io_test_support.hpp"
#include "ngi/error.hpp"
#include "ngi/image_io.hpp"
#include "ngi/tensor.hpp"
#include "test_support.hpp"

using Catch::Matchers::Contains;
using ngi::test::TempDir;

namespace {

ngi::Image random_image(int w, int h, int c, std::mt19937& rng, float lo, float hi) {
    ngi::Image img(w, h, c);
    img.data = ngi::test::random_vector(img.data.size(), rng, lo, hi);
    return img;
}

// ---- a minimal PNG encoder (stored deflate blocks, no compression), independent of libpng ----
void put32(std::string& s, std::uint32_t v) {
    for (int i = 3; i >= 0; --i) s += char((v >> (8 * i)) & 0xff);
}
std::uint32_t crc32(const std::string& s) {
    std::uint32_t c = 0xffffffffu;
    for (unsigned char b : s) {
        c ^= b;
        for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xedb88320u ^ (c >> 1) : c >> 1;
    }
    return ~c;
}
void chunk(std::string& png, const char* type, const std::string& data) {
    put32(png, std::uint32_t(data.size()));
    const std::string body = type + data;
    png += body;
    put32(png, crc32(body));
}
// rows: the unfiltered scanlines (without the filter byte). adam7_pixel_bytes > 0: write them Adam7-interlaced
// (bytes per pixel of the 8/16-bit formats used here).
std::string make_png(int w, int h, int bit_depth, int color_type, const std::vector<std::string>& rows,
                     const std::string& plte = "", const std::string& trns = "", int adam7_pixel_bytes = 0) {
    std::string raw;
    if (adam7_pixel_bytes == 0) {
        for (const auto& r : rows) raw += '\0' + r;  // filter type 0 (None)
    } else {
        const int pass[7][4] = {{0, 0, 8, 8}, {4, 0, 8, 8}, {0, 4, 4, 8}, {2, 0, 4, 4}, {0, 2, 2, 4}, {1, 0, 2, 2}, {0, 1, 1, 2}};
        for (const auto& p : pass) {  // {x0, y0, dx, dy}; passes with no pixels write no rows
            if (p[0] >= w) continue;
            for (int y = p[1]; y < h; y += p[3]) {
                raw += '\0';
                for (int x = p[0]; x < w; x += p[2]) raw += rows[y].substr(std::size_t(x) * adam7_pixel_bytes, adam7_pixel_bytes);
            }
        }
    }
    std::string z = "\x78\x01";
    for (std::size_t off = 0; off < raw.size() || off == 0; off += 65535) {
        const std::size_t n = std::min<std::size_t>(65535, raw.size() - off);
        z += char(off + n >= raw.size() ? 1 : 0);
        z += char(n & 0xff); z += char(n >> 8); z += char(~n & 0xff); z += char((~n >> 8) & 0xff);
        z += raw.substr(off, n);
    }
    std::uint32_t a = 1, b = 0;
    for (unsigned char ch : raw) { a = (a + ch) % 65521; b = (b + a) % 65521; }
    put32(z, b << 16 | a);
    std::string ihdr;
    put32(ihdr, std::uint32_t(w));
    put32(ihdr, std::uint32_t(h));
    ihdr += char(bit_depth); ihdr += char(color_type); ihdr += std::string(2, '\0'); ihdr += char(adam7_pixel_bytes ? 1 : 0);
    std::string png = "\x89PNG\r\n\x1a\n";
    chunk(png, "IHDR", ihdr);
    if (!plte.empty()) chunk(png, "PLTE", plte);
    if (!trns.empty()) chunk(png, "tRNS", trns);
    chunk(png, "IDAT", z);
    chunk(png, "IEND", "");
    return png;
}

double max_rel_diff(const std::vector<float>& a, const std::vector<float>& b) {
    double m = 0;
    for (std::size_t i = 0; i < a.size(); ++i)
        m = std::max(m, std::abs(double(a[i]) - b[i]) / std::max(1e-30, std::abs(double(b[i]))));
    return m;
}

}  // namespace

TEST_CASE("EXR round trips in float (exact) and half (rounded), 1..12 channels", "[io]") {
    TempDir dir("exr");
    std::mt19937 rng(1);
    for (int channels : {1, 2, 3, 4, 5, 12}) {
        const ngi::Image img = random_image(37, 21, channels, rng, -3000.0f, 3000.0f);
        INFO(channels << " channels");
        std::vector<std::string> names;

        ngi::write_exr(dir / "f.exr", img, ngi::ExrPixelType::Float);
        const ngi::Image f = ngi::read_exr(dir / "f.exr", &names);
        REQUIRE(f.width == 37);
        REQUIRE(f.height == 21);
        REQUIRE(f.channels == channels);
        CHECK(f.data == img.data);
        CHECK(names == ngi::exr_channel_names(channels));

        ngi::write_exr(dir / "h.exr", img, ngi::ExrPixelType::Half);
        const ngi::Image h = ngi::read_exr(dir / "h.exr");
        REQUIRE(h.data.size() == img.data.size());
        CHECK(max_rel_diff(h.data, img.data) <= std::ldexp(1.0, -11));  // round to nearest, 10-bit mantissa
    }
    CHECK(ngi::exr_channel_names(1) == std::vector<std::string>{"Y"});
    CHECK(ngi::exr_channel_names(3) == std::vector<std::string>{"R", "G", "B"});
    CHECK(ngi::exr_channel_names(4) == std::vector<std::string>{"R", "G", "B", "A"});
    CHECK(ngi::exr_channel_names(12)[10] == "c10");
    CHECK(dir.list() == std::vector<std::string>{"f.exr", "h.exr"});  // no temporaries left
}

TEST_CASE("EXR channel order of foreign files: R, G, B, others in natural order, A, by layer", "[io]") {
    TempDir dir("exr-names");
    // Channel k holds the value k, so the order read back is visible in the data.
    auto check = [&](const std::vector<std::string>& written, const std::vector<std::string>& expected) {
        ngi::Image img(2, 2, int(written.size()));
        for (int c = 0; c < img.channels; ++c)
            for (std::size_t i = 0; i < img.plane(); ++i) img.data[c * img.plane() + i] = float(c);
        ngi::write_exr(dir / "n.exr", img, ngi::ExrPixelType::Half, written);
        std::vector<std::string> names;
        const ngi::Image r = ngi::read_exr(dir / "n.exr", &names);
        CHECK(names == expected);
        for (int c = 0; c < r.channels; ++c) {
            const auto k = std::find(written.begin(), written.end(), names[c]) - written.begin();
            CHECK(r.at(c, 1, 1) == float(k));
        }
    };
    check({"A", "B", "G", "R"}, {"R", "G", "B", "A"});
    check({"Z", "Y", "X"}, {"X", "Y", "Z"});
    check({"Y", "A"}, {"Y", "A"});
    check({"R", "G", "B", "Z"}, {"R", "G", "B", "Z"});
    check({"c10", "c2", "c1", "c0"}, {"c0", "c1", "c2", "c10"});
    check({"diffuse.B", "diffuse.R", "diffuse.G", "R", "G", "B", "layer2.A", "layer10.R", "layer2.R"},
          {"R", "G", "B", "diffuse.R", "diffuse.G", "diffuse.B", "layer2.R", "layer2.A", "layer10.R"});
    CHECK_THROWS_WITH(ngi::write_exr(dir / "d.exr", ngi::Image(2, 2, 2), ngi::ExrPixelType::Half, {"R", "R"}),
                      Contains("d.exr") && Contains("distinct"));
    CHECK_THROWS_WITH(ngi::write_exr(dir / "d.exr", ngi::Image(2, 2, 2), ngi::ExrPixelType::Half, {"R"}),
                      Contains("2 distinct"));
}

TEST_CASE("EXR: the image is the display window, pixels outside the data window are 0", "[io]") {
    TempDir dir("exr-window");
    std::mt19937 rng(6);
    const ngi::Image img = random_image(5, 4, 3, rng, 1.0f, 2.0f);
    ngi::write_exr(dir / "w.exr", img, ngi::ExrPixelType::Float);
    // Patch the header's displayWindow (box2i: xMin, yMin, xMax, yMax, little-endian int32) to (-1, -2)..(3, 3):
    // the data window (0, 0)..(4, 3) now sits 1 column right and 2 rows down in a 5x6 image, and its last column
    // falls outside. Same byte count, so the chunk offsets stay valid.
    std::string bytes = ngi::test::slurp(dir / "w.exr");
    const std::string key = std::string("displayWindow\0box2i\0", 20);
    const std::size_t at = bytes.find(key);
    REQUIRE(at != std::string::npos);
    const std::int32_t box[4] = {-1, -2, 3, 3};
    std::memcpy(&bytes[at + key.size() + 4], box, sizeof box);
    ngi::test::spit(dir / "w.exr", bytes);
    const ngi::Image r = ngi::read_exr(dir / "w.exr");
    REQUIRE(r.width == 5);
    REQUIRE(r.height == 6);
    for (int c = 0; c < 3; ++c)
        for (int y = 0; y < 6; ++y)
            for (int x = 0; x < 5; ++x) {
                const int sx = x - 1, sy = y - 2;  // data-window pixel shown at (x, y)
                const bool inside = sx >= 0 && sx < 5 && sy >= 0 && sy < 4;
                CHECK(r.at(c, y, x) == (inside ? img.at(c, sy, sx) : 0.0f));
            }
}

TEST_CASE("EXR: a data window far from the origin reads without pointer overflow", "[io]") {
    // OpenEXR addresses pixels from a base pointer (min.x + min.y * width) pixels before the buffer. With the window
    // at y = 1e9 (OpenEXR's own limit is about 1.07e9) and 65,536 pixels wide that is 2.6e14 bytes: below every heap
    // address, so computing it as a pointer wrapped around (undefined behaviour; the fuzzer found it, UBSan reports
    // it in the sanitize stage).
    TempDir dir("exr-far");
    const int w = 65536, y0 = 1000000000, x0 = -7;
    Imf::Header header(Imath::Box2i({x0, y0}, {x0 + w - 1, y0}), Imath::Box2i({x0, y0}, {x0 + w - 1, y0}));
    header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
    header.compression() = Imf::NO_COMPRESSION;  // the reader's size check wants bytes behind the pixels
    std::vector<float> px(w);
    for (int i = 0; i < w; ++i) px[std::size_t(i)] = float(i % 251);
    {
        Imf::OutputFile out((dir / "far.exr").c_str(), header);
        Imf::FrameBuffer fb;
        // Written with OpenEXR's own convention, from an integer address: the test must not do what it tests against.
        const std::uintptr_t base = reinterpret_cast<std::uintptr_t>(px.data()) -
                                    (std::uintptr_t(std::intptr_t(x0)) + std::uintptr_t(y0) * std::uintptr_t(w)) * 4u;
        fb.insert("Y", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(base), sizeof(float), sizeof(float) * w));
        out.setFrameBuffer(fb);
        out.writePixels(1);
    }
    const ngi::Image r = ngi::read_exr(dir / "far.exr");
    REQUIRE(r.width == w);
    REQUIRE(r.height == 1);
    CHECK(r.data == px);
    // The fuzzer's input itself (a mutated header: a data window at 1.85e8 with garbage beyond): refused cleanly.
    const unsigned char fuzz[] = {
        0x76, 0x2f, 0x31, 0x01, 0x02, 0x00, 0x00, 0x00, 0x63, 0x68, 0x61, 0x6e, 0x6e, 0x65, 0x6c, 0x73, 0x00, 0x63,
        0x68, 0x6c, 0x69, 0x73, 0x74, 0x00, 0x37, 0x00, 0x00, 0x00, 0x42, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00,
        0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x47, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00,
        0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x52, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00,
        0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x63, 0x6f, 0x6d, 0x70, 0x72, 0x65, 0x73,
        0x73, 0x69, 0x6f, 0x6e, 0x00, 0x63, 0x6f, 0x6d, 0x70, 0x72, 0x65, 0x73, 0x73, 0x69, 0x6f, 0x6e, 0x00, 0x01,
        0x00, 0x00, 0x00, 0x05, 0x64, 0x61, 0x74, 0x61, 0x57, 0x69, 0x6e, 0x64, 0x6f, 0x77, 0x00, 0x62, 0x6f, 0x78,
        0x32, 0x69, 0x00, 0x10, 0x00, 0x00, 0x00, 0x0b, 0x0b, 0x0b, 0x0b, 0x0b, 0x0b, 0x0b, 0x0b, 0x0b, 0x0b, 0x29,
        0x0b, 0x0b, 0x0b, 0x0b, 0x0b, 0x0b, 0x02, 0x00, 0x0b, 0x0b, 0x0b, 0x0b, 0x0b, 0x0b, 0x0b, 0x0b, 0x0b, 0x0b,
        0x0b, 0x0b, 0x0b, 0x0b, 0x00, 0x00, 0x00, 0x00, 0x00, 0x32, 0x69, 0x00, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00,
        0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x63, 0x6f, 0x6d, 0x70, 0x72, 0x65, 0x73, 0x73, 0x69, 0x6f, 0x6e, 0x00,
        0x63, 0x6f, 0x6d, 0x70, 0x06, 0x36, 0xbe, 0xcd, 0x37,
    };
    ngi::test::spit(dir / "fuzz.exr", std::string(reinterpret_cast<const char*>(fuzz), sizeof fuzz));
    CHECK_THROWS_AS(ngi::read_exr(dir / "fuzz.exr"), ngi::InputError);
}

TEST_CASE("EXR half: finite values beyond the half range clamp, NaN and Inf are kept", "[io]") {
    TempDir dir("exr-half");
    ngi::Image img(4, 1, 1);
    img.data = {1e6f, -1e6f, std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN()};
    ngi::write_exr(dir / "h.exr", img, ngi::ExrPixelType::Half);
    const ngi::Image h = ngi::read_exr(dir / "h.exr");
    CHECK(h.data[0] == 65504.0f);
    CHECK(h.data[1] == -65504.0f);
    CHECK(std::isinf(h.data[2]));
    CHECK(std::isnan(h.data[3]));
}

TEST_CASE("PNG: 8-bit round trips, sRGB, and 16-bit / palette files from an independent encoder", "[io]") {
    TempDir dir("png");
    std::mt19937 rng(2);
    for (int channels = 1; channels <= 4; ++channels) {
        INFO(channels << " channels");
        ngi::Image img = random_image(19, 7, channels, rng, 0.0f, 1.0f);
        ngi::write_png(dir / "a.png", img);
        const ngi::Image r = ngi::read_png(dir / "a.png");
        REQUIRE(r.channels == channels);
        REQUIRE(r.width == 19);
        CHECK(ngi::test::max_abs_diff(r.data, img.data) <= 0.5 / 255 + 1e-7);
        // Exact 8-bit levels survive a second round trip bit for bit.
        ngi::write_png(dir / "b.png", r);
        CHECK(ngi::read_png(dir / "b.png").data == r.data);
        // sRGB: encode on write, decode on read; alpha (2 and 4 channels) untouched.
        ngi::write_png(dir / "s.png", img, ngi::PngEncoding::Srgb);
        const ngi::Image s = ngi::read_png(dir / "s.png", ngi::PngEncoding::Srgb);
        CHECK(ngi::test::max_abs_diff(s.data, img.data) < 0.011);  // one 8-bit sRGB step near black is ~0.0003..0.009
        const ngi::Image s_raw = ngi::read_png(dir / "s.png");
        if (channels == 2 || channels == 4) {
            const std::size_t a = std::size_t(channels - 1) * img.plane();
            CHECK(ngi::test::max_abs_diff({s_raw.data.begin() + a, s_raw.data.end()},
                                          {img.data.begin() + a, img.data.end()}) <= 0.5 / 255 + 1e-7);
        }
    }
    // Out-of-range and NaN values are clamped on write.
    ngi::Image odd(3, 1, 1);
    odd.data = {-0.5f, 7.0f, std::numeric_limits<float>::quiet_NaN()};
    ngi::write_png(dir / "c.png", odd);
    CHECK(ngi::read_png(dir / "c.png").data == std::vector<float>{0.0f, 1.0f, 0.0f});
    // The sRGB curve itself: level 188 is 0.50289 linear.
    ngi::Image mid(1, 1, 1, 188.0f / 255.0f);
    ngi::write_png(dir / "m.png", mid);
    CHECK(ngi::read_png(dir / "m.png", ngi::PngEncoding::Srgb).data[0] == Approx(0.50289).margin(1e-4));

    // 16-bit RGB, 2x2: samples big-endian.
    auto be16 = [](unsigned v) { return std::string{char(v >> 8), char(v & 0xff)}; };
    const unsigned v16[2][2][3] = {{{0, 65535, 1}, {256, 12345, 65534}}, {{40000, 2, 3}, {7, 8, 9}}};
    std::vector<std::string> rows16(2);
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 2; ++x)
            for (int c = 0; c < 3; ++c) rows16[y] += be16(v16[y][x][c]);
    ngi::test::spit(dir / "d16.png", make_png(2, 2, 16, 2, rows16));
    const ngi::Image p16 = ngi::read_png(dir / "d16.png");
    REQUIRE(p16.channels == 3);
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 2; ++x)
            for (int c = 0; c < 3; ++c) CHECK(p16.at(c, y, x) == Approx(v16[y][x][c] / 65535.0).margin(1e-7));

    // The same pixels Adam7-interlaced, and a larger interlaced 8-bit RGB image against its plain twin.
    ngi::test::spit(dir / "d16i.png", make_png(2, 2, 16, 2, rows16, "", "", 6));
    CHECK(ngi::read_png(dir / "d16i.png").data == p16.data);
    std::vector<std::string> rows8(13);
    for (int y = 0; y < 13; ++y)
        for (int x = 0; x < 11 * 3; ++x) rows8[y] += char(rng() & 0xff);
    ngi::test::spit(dir / "plain.png", make_png(11, 13, 8, 2, rows8));
    ngi::test::spit(dir / "adam7.png", make_png(11, 13, 8, 2, rows8, "", "", 3));
    const ngi::Image plain = ngi::read_png(dir / "plain.png");
    CHECK(plain.at(1, 12, 10) == float((unsigned char)rows8[12][10 * 3 + 1]) / 255.0f);
    CHECK(ngi::read_png(dir / "adam7.png").data == plain.data);

    // 8-bit palette with transparency -> RGBA.
    const std::string plte = std::string("\xff\x00\x00", 3) + std::string("\x00\x80\x00", 3);
    ngi::test::spit(dir / "pal.png", make_png(2, 1, 8, 3, {std::string("\x00\x01", 2)}, plte, std::string("\x40", 1)));
    const ngi::Image pal = ngi::read_png(dir / "pal.png");
    REQUIRE(pal.channels == 4);
    CHECK(pal.data == std::vector<float>{1.0f, 0.0f, 0.0f, 128.0f / 255.0f, 0.0f, 0.0f, 64.0f / 255.0f, 1.0f});
}

TEST_CASE("read_image / write_image choose the format by extension, .npy holds [C, H, W]", "[io]") {
    TempDir dir("any");
    std::mt19937 rng(3);
    const ngi::Image img = random_image(9, 5, 3, rng, -2.0f, 2.0f);
    for (const char* name : {"x.exr", "X.EXR", "x.npy"}) {
        ngi::write_image(dir / name, img);
        const ngi::Image r = ngi::read_image(dir / name);
        CHECK(r.width == 9);
        CHECK(r.height == 5);
        CHECK(r.data == img.data);  // float EXR and float32 .npy are lossless
    }
    CHECK(ngi::read_npy(dir / "x.npy").shape == std::vector<int>{3, 5, 9});
    ngi::Tensor hw({5, 9}), nchw({1, 3, 5, 9});
    ngi::write_npy(dir / "hw.npy", hw);
    ngi::write_npy(dir / "nchw.npy", nchw);
    CHECK(ngi::read_image(dir / "hw.npy").channels == 1);
    CHECK(ngi::read_image(dir / "nchw.npy").channels == 3);
    ngi::write_npy(dir / "bad.npy", ngi::Tensor({2, 3, 5, 9}));
    CHECK_THROWS_WITH(ngi::read_image(dir / "bad.npy"), Contains("bad.npy") && Contains("[2, 3, 5, 9]"));
    CHECK_THROWS_WITH(ngi::read_image(dir / "x.tiff"), Contains("x.tiff") && Contains("unknown image format"));
    CHECK_THROWS_WITH(ngi::write_image(dir / "x.jpg", img), Contains("x.jpg"));
    ngi::write_image(dir / "x.png", random_image(9, 5, 3, rng, 0.0f, 1.0f));
    CHECK(ngi::read_image(dir / "x.png").channels == 3);
}

TEST_CASE("bad image files: missing, wrong format, truncated -> InputError naming the file", "[io]") {
    TempDir dir("bad");
    std::mt19937 rng(4);
    const ngi::Image img = random_image(64, 48, 3, rng, 0.0f, 1.0f);
    ngi::write_exr(dir / "good.exr", img, ngi::ExrPixelType::Half);
    ngi::write_png(dir / "good.png", img);

    CHECK_THROWS_WITH(ngi::read_exr(dir / "none.exr"), Contains("none.exr") && Contains("cannot open"));
    CHECK_THROWS_WITH(ngi::read_png(dir / "none.png"), Contains("none.png") && Contains("cannot open"));
    CHECK_THROWS_WITH(ngi::read_exr(dir.path.string()), Contains("directory"));
    CHECK_THROWS_WITH(ngi::read_exr(dir / "good.png"), Contains("good.png") && Contains("not an OpenEXR file"));
    CHECK_THROWS_WITH(ngi::read_png(dir / "good.exr"), Contains("good.exr") && Contains("not a PNG file"));
    ngi::test::spit(dir / "empty.exr", "");
    CHECK_THROWS_WITH(ngi::read_exr(dir / "empty.exr"), Contains("empty.exr") && Contains("not an OpenEXR"));

    // Truncation anywhere: in the header, in the offset table, in the pixel data, one byte short.
    const std::string exr = ngi::test::slurp(dir / "good.exr"), png = ngi::test::slurp(dir / "good.png");
    for (double f : {0.01, 0.1, 0.5, 0.9}) {
        for (const auto& [name, bytes] : {std::pair{"cut.exr", exr}, std::pair{"cut.png", png}}) {
            const std::size_t n = std::max<std::size_t>(8, std::size_t(f * bytes.size()));
            INFO(name << " cut to " << n << " of " << bytes.size() << " bytes");
            ngi::test::spit(dir / name, bytes.substr(0, n));
            CHECK_THROWS_AS(ngi::read_image(dir / name), ngi::InputError);
            CHECK_THROWS_WITH(ngi::read_image(dir / name), Contains(name));
        }
    }
    ngi::test::spit(dir / "cut.png", png.substr(0, png.size() - 1));
    CHECK_THROWS_WITH(ngi::read_png(dir / "cut.png"), Contains("cut.png") && Contains("truncated"));
    ngi::test::spit(dir / "cut.exr", exr.substr(0, exr.size() - 1));
    CHECK_THROWS_WITH(ngi::read_exr(dir / "cut.exr"), Contains("cut.exr"));

    // Writes that cannot be done: bad images, a folder that does not exist.
    CHECK_THROWS_WITH(ngi::write_png(dir / "five.png", ngi::Image(2, 2, 5)), Contains("five.png") && Contains("1 to 4"));
    ngi::Image broken(4, 4, 3);
    broken.data.resize(7);
    CHECK_THROWS_WITH(ngi::write_exr(dir / "broken.exr", broken), Contains("broken.exr") && Contains("invalid image"));
    CHECK_THROWS_WITH(ngi::write_exr(dir / "no/such/dir/x.exr", img), Contains("x.exr") && Contains("cannot create"));
}

TEST_CASE("a failing write leaves neither a partial file nor a temporary, and keeps the old file", "[io]") {
    TempDir dir("failwrite");
    std::mt19937 rng(5);
    const ngi::Image big = random_image(256, 256, 3, rng, 0.0f, 1.0f);  // incompressible: ~780 KB as float
    const ngi::Image small = random_image(8, 8, 3, rng, 0.0f, 1.0f);
    ngi::write_exr(dir / "keep.exr", small, ngi::ExrPixelType::Float);
    const std::string before = ngi::test::slurp(dir / "keep.exr");
    {
        ngi::test::FileSizeLimit limit(64 * 1024);  // the "disk" fills up in the middle of the pixel data
        CHECK_THROWS_WITH(ngi::write_exr(dir / "new.exr", big, ngi::ExrPixelType::Float),
                          Contains("new.exr") && Contains("write failed"));
        CHECK_THROWS_WITH(ngi::write_exr(dir / "keep.exr", big, ngi::ExrPixelType::Float), Contains("keep.exr"));
        CHECK_THROWS_WITH(ngi::write_png(dir / "new.png", random_image(512, 512, 3, rng, 0.0f, 1.0f)),
                          Contains("new.png"));
        CHECK_THROWS_WITH(ngi::write_image(dir / "new.npy", big), Contains("new.npy"));
    }
    CHECK(dir.list() == std::vector<std::string>{"keep.exr"});
    CHECK(ngi::test::slurp(dir / "keep.exr") == before);

    // The target is a folder: the file is complete, the rename fails, the temporary is removed.
    std::filesystem::create_directory(dir / "taken.exr");
    CHECK_THROWS_WITH(ngi::write_exr(dir / "taken.exr", small), Contains("taken.exr"));
    CHECK(dir.list() == std::vector<std::string>{"keep.exr", "taken.exr"});
}
