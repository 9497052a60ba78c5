// Untrusted sizes and values in input files (findings of the fuzz targets in fuzz/ and of a manual probe): each
// must be an InputError naming the file and the field, never a wrapped-around size, a std::bad_alloc, a
// std::out_of_range from stoi, or a read that never ends.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <future>
#include <nlohmann/json.hpp>

#include "io/decode.hpp"
#include "base/file_util.hpp"
#include "io_test_support.hpp"
#include "models/safetensors.hpp"
#include "models/family.hpp"
#include "ngi/dataset.hpp"
#include "ngi/error.hpp"
#include "ngi/image_io.hpp"
#include "ngi/mesh.hpp"
#include "ngi/scene.hpp"
#include "ngi/tensor.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using ngi::test::TempDir;

namespace {

std::string npy(const std::string& descr, const std::string& shape, const std::string& data) {
    std::string header = "{'descr': '" + descr + "', 'fortran_order': False, 'shape': " + shape + ", }\n";
    std::string b("\x93NUMPY\x01\x00", 8);
    b += char(header.size() & 0xff);
    b += char(header.size() >> 8);
    return b + header + data;
}

std::string safetensors(const nlohmann::json& header, const std::string& data) {
    const std::string h = header.dump();
    std::string b(8, '\0');
    for (int i = 0; i < 8; ++i) b[i] = char((std::uint64_t(h.size()) >> (8 * i)) & 0xff);
    return b + h + data;
}

nlohmann::json good_config() {
    return {{"format_version", 1}, {"family", "pix2pix_unet"}, {"input_nc", 12}, {"output_nc", 3}, {"ngf", 64},
            {"num_downs", 8}, {"bn_mode", "per_image"}, {"bn_eps", 1e-5}, {"dropout", "off"}, {"dropout_p", 0.5},
            {"dropout_seed", 0}, {"leaky_slope", 0.2}, {"input_range", {-1, 1}}, {"output_range", {-1, 1}}};
}

std::uint32_t crc32(const std::string& s) {
    std::uint32_t c = 0xffffffffu;
    for (unsigned char b : s) {
        c ^= b;
        for (int k = 0; k < 8; ++k) c = c & 1 ? 0xedb88320u ^ (c >> 1) : c >> 1;
    }
    return ~c;
}

void put_be32(std::string& s, std::size_t at, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) s[at + i] = char((v >> (24 - 8 * i)) & 0xff);
}

// The InputError message of `read` on the FIFO `fifo` ("" if it returned). A reader that opens the FIFO blocking
// waits for a writer forever: after 10 s the test plays that writer (open + close gives the reader end of file),
// so a regression fails here instead of hanging the suite.
std::string error_on_fifo(const std::string& fifo, const std::function<void()>& read) {
    auto result = std::async(std::launch::async, [&]() -> std::string {
        try {
            read();
        } catch (const ngi::InputError& e) {
            return e.what();
        }
        return "";
    });
    if (result.wait_for(std::chrono::seconds(10)) != std::future_status::ready) {
        const int fd = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);
        if (fd >= 0) ::close(fd);
        result.wait();
        FAIL("reading " << fifo << " blocked for 10 s (it opened the FIFO)");
    }
    return result.get();
}

}  // namespace

TEST_CASE("read_file refuses directories, devices, FIFOs and files over the size cap", "[io][limits]") {
    TempDir dir("limits-file");
    // A directory used to reach the caller as "basic_filebuf..." (ifstream) and /dev/zero grew without bound.
    CHECK_THROWS_WITH(ngi::detail::read_file(dir.path.string()), Contains(dir.path.string()) && Contains("directory"));
    CHECK_THROWS_WITH(ngi::detail::read_file("/dev/zero"), Contains("/dev/zero") && Contains("not a regular file"));
    REQUIRE(::mkfifo((dir / "fifo").c_str(), 0600) == 0);
    CHECK_THROWS_WITH(ngi::detail::read_file(dir / "fifo"), Contains("fifo") && Contains("not a regular file"));
    ngi::test::spit(dir / "big.bin", std::string(100, 'x'));
    CHECK_THROWS_WITH(ngi::detail::read_file(dir / "big.bin", "read", 64),
                      Contains("big.bin") && Contains("100 bytes") && Contains("limit of 64"));
    CHECK(ngi::detail::read_file(dir / "big.bin", "read", 100).size() == 100);
    // Every reader goes through it.
    CHECK_THROWS_WITH(ngi::read_npy("/dev/zero"), Contains("not a regular file"));
    CHECK_THROWS_WITH(ngi::read_exr(dir.path.string()), Contains("directory"));
    CHECK_THROWS_WITH(ngi::read_png("/dev/zero"), Contains("not a regular file"));
    CHECK_THROWS_WITH(ngi::detail::read_safetensors(dir.path.string()),
                      Contains("load model") && Contains("directory"));
    CHECK_THROWS_WITH(ngi::detail::read_safetensors("/dev/zero"), Contains("load model /dev/zero"));
    CHECK_THROWS_WITH(ngi::DatasetConfig::load("/dev/zero"), Contains("dataset config /dev/zero"));
    CHECK_THROWS_WITH(ngi::DatasetConfig::load(dir.path.string()), Contains("dataset config") && Contains("directory"));
}

TEST_CASE("a FIFO where a file is expected is refused at once by every reader", "[io][limits]") {
    TempDir dir("limits-fifo");
    // The .vox loader once opened its file with a blocking std::ifstream: `ngi render --scene x.vox`, voxel-data and
    // ao-data waited forever for a writer. Every reader now goes through read_file's rule (stat first: only
    // regular files are opened).
    for (const char* name : {"x.vox", "x.obj", "x.ply", "m.safetensors", "c.json", "i.npy"})
        REQUIRE(::mkfifo((dir / name).c_str(), 0600) == 0);
    CHECK_THAT(error_on_fifo(dir / "x.vox", [&] { ngi::make_scene(dir / "x.vox"); }),
               Contains("x.vox") && Contains("FIFO"));
    CHECK_THAT(error_on_fifo(dir / "x.vox", [&] { ngi::load_vox(dir / "x.vox"); }), Contains("FIFO"));
    // The mesh loader follows the same rule (its sidecar files too: tests/test_mesh.cpp).
    CHECK_THAT(error_on_fifo(dir / "x.obj", [&] { ngi::make_scene(dir / "x.obj"); }),
               Contains("x.obj") && Contains("FIFO"));
    CHECK_THAT(error_on_fifo(dir / "x.ply", [&] { ngi::load_mesh(dir / "x.ply"); }), Contains("FIFO"));
    CHECK_THAT(error_on_fifo(dir / "m.safetensors", [&] { ngi::detail::read_safetensors(dir / "m.safetensors"); }),
               Contains("load model") && Contains("FIFO"));
    CHECK_THAT(error_on_fifo(dir / "c.json", [&] { ngi::DatasetConfig::load(dir / "c.json"); }),
               Contains("dataset config") && Contains("FIFO"));
    CHECK_THAT(error_on_fifo(dir / "i.npy", [&] { ngi::read_npy(dir / "i.npy"); }), Contains("FIFO"));
    // The rule itself: judged by stat, so nothing is opened; sockets, directories and devices too; absent passes.
    CHECK_THROWS_WITH(ngi::detail::require_readable_file(dir / "x.vox", "load scene"),
                      Contains("load scene") && Contains("it is a FIFO, not a regular file"));
    CHECK_THROWS_WITH(ngi::detail::require_readable_file("/dev/null"), Contains("device"));
    CHECK_THROWS_WITH(ngi::detail::require_readable_file(dir.path.string()), Contains("directory"));
    CHECK_NOTHROW(ngi::detail::require_readable_file(dir / "absent.vox"));
}

TEST_CASE(".npy: negative, oversized and overflowing shapes are refused", "[io][limits]") {
    const std::string data(4 * 12 * 32 * 32, '\0');
    // The old regex read the digits of "-32" as 32 and ran the file.
    CHECK_THROWS_WITH(ngi::detail::decode_npy(npy("<f4", "(1, 12, -32, 32)", data), "neg.npy"),
                      Contains("neg.npy") && Contains("-32"));
    CHECK(ngi::detail::decode_npy(npy("<f4", "(1, 12, 32, 32)", data), "ok.npy").data.size() == 12 * 32 * 32);
    // 2^30 * 2^30 * 16 elements wrapped to 0 bytes in size_t and passed the size check.
    CHECK_THROWS_WITH(ngi::detail::decode_npy(npy("<f4", "(1073741824, 1073741824, 16)", ""), "wrap.npy"),
                      Contains("wrap.npy") && Contains("truncated"));
    // std::stoi threw std::out_of_range ("stoi") for a dimension beyond int.
    CHECK_THROWS_WITH(ngi::detail::decode_npy(npy("<f4", "(99999999999,)", ""), "big.npy"),
                      Contains("big.npy") && Contains("99999999999"));
    CHECK_THROWS_AS(ngi::detail::decode_npy(npy("<f4", "(3, x)", ""), "x.npy"), ngi::InputError);
    CHECK_THROWS_WITH(ngi::detail::decode_npy(npy("<f4", "(3,)", "") + "junk", "cut.npy"), Contains("truncated"));
    // A long header string overflowed the stack in libstdc++'s recursive std::regex.
    const std::string long_descr(60000, 'f');
    CHECK_THROWS_WITH(ngi::detail::decode_npy(npy(long_descr, "(1,)", "abcd"), "long.npy"),
                      Contains("long.npy") && Contains("not supported"));
    CHECK(ngi::detail::decode_npy(npy("<f4", "(3,)", std::string(12, '\0')), "one.npy").shape ==
          std::vector<int>{3});
}

TEST_CASE("safetensors: dimensions and offsets are range-checked, byte counts cannot overflow", "[model][limits]") {
    auto entry = [](nlohmann::json shape, nlohmann::json offsets) {
        return nlohmann::json{{"t", {{"dtype", "F32"}, {"shape", shape}, {"data_offsets", offsets}}}};
    };
    // [2^30, 2^30, 16] x 4 bytes wrapped to 0 and matched data_offsets [0, 0].
    CHECK_THROWS_WITH(ngi::detail::parse_safetensors(
                          safetensors(entry({1073741824, 1073741824, 16}, {0, 0}), ""), "wrap.safetensors"),
                      Contains("wrap.safetensors") && Contains("tensor 't'") && Contains("needs more than"));
    // 2^32 + 4 was read as 4 by get<int>.
    CHECK_THROWS_WITH(ngi::detail::parse_safetensors(safetensors(entry({4294967300ll}, {0, 16}), std::string(16, '\0')),
                                                     "trunc.safetensors"),
                      Contains("every dimension must be an integer"));
    CHECK_THROWS_WITH(ngi::detail::parse_safetensors(safetensors(entry({-1}, {0, 0}), ""), "neg.safetensors"),
                      Contains("every dimension"));
    CHECK_THROWS_WITH(ngi::detail::parse_safetensors(safetensors(entry({1}, {-1, 3}), "abcd"), "off.safetensors"),
                      Contains("data_offsets must be"));
    CHECK_THROWS_WITH(ngi::detail::parse_safetensors(safetensors(entry({1}, {0, 4, 8}), "abcd"), "off3.safetensors"),
                      Contains("data_offsets must be"));
    const auto ok = ngi::detail::parse_safetensors(safetensors(entry({2, 1}, {0, 8}), std::string(8, '\0')), "ok");
    CHECK(ok.tensors.at("t").data.size() == 2);
}

TEST_CASE("model config: every field is type- and range-checked, naming the field", "[model][limits]") {
    CHECK(ngi::detail::parse_model_config(good_config().dump(), "m.safetensors").unet.ngf == 64);
    auto refuse = [](const char* key, nlohmann::json value, const std::string& expect) {
        nlohmann::json c = good_config();
        c[key] = value;
        INFO(key << " = " << value.dump());
        CHECK_THROWS_WITH(ngi::detail::parse_model_config(c.dump(), "m.safetensors"),
                          Contains("m.safetensors") && Contains(std::string("'") + key + "'") && Contains(expect));
    };
    refuse("bn_eps", 0, "(0, 1]");
    refuse("bn_eps", -1e-5, "(0, 1]");
    refuse("bn_eps", "1e-5", "(0, 1]");
    refuse("leaky_slope", 1e300, "[0, 1]");
    refuse("leaky_slope", -0.2, "[0, 1]");
    refuse("format_version", 99, "newer than the newest this reader knows (1)");
    refuse("format_version", 0, "1..1");
    refuse("ngf", 4294967300ll, "1..8192");  // was read as 4
    refuse("ngf", 0, "1..8192");
    refuse("input_nc", 12.5, "an integer");
    refuse("output_nc", -3, "an integer");
    refuse("num_downs", 4, "5..12");
    refuse("dropout_p", 1.0, "[0, 1)");
    refuse("dropout_seed", -1, "0..4294967295");
    refuse("dropout_seed", 4294967296ll, "0..4294967295");
    refuse("bn_mode", "train", "\"running\" | \"per_image\"");
    refuse("dropout", true, "\"off\" | \"seeded\"");
    refuse("input_layout", nlohmann::json::array({"a", "b"}), "input_nc (12) long");
    refuse("input_range", nlohmann::json::array({1, -1}), "lo < hi");
    refuse("output_range", nlohmann::json::array({0}), "lo < hi");
    refuse("norm", "instance", "\"batch\"");
    refuse("source", 7, "a string");
    refuse("required", "ngf", "a list of field names");
    refuse("required", nlohmann::json::array({"ngf", "sparse_weights"}), "'sparse_weights', which this reader does not know");
    {
        nlohmann::json c = good_config();
        c["required"] = nlohmann::json::array({"ngf", "bn_mode"});
        c["some_future_hint"] = 3;  // unknown but optional: ignored
        CHECK(ngi::detail::parse_model_config(c.dump(), "m.safetensors").unet.ngf == 64);
    }
    nlohmann::json di = good_config();
    di["family"] = "deepillumination";
    di["num_downs"] = 7;
    CHECK_THROWS_WITH(ngi::detail::parse_model_config(di.dump(), "di.safetensors"), Contains("'num_downs'") &&
                                                                                      Contains("8..8"));
    nlohmann::json missing = good_config();
    missing.erase("ngf");
    CHECK_THROWS_WITH(ngi::detail::parse_model_config(missing.dump(), "m"), Contains("'ngf'") && Contains("missing"));
    CHECK_THROWS_WITH(ngi::detail::parse_model_config("[1, 2]", "arr.safetensors"), Contains("not a JSON object"));
}

TEST_CASE("EXR and PNG headers that promise more pixels than the file holds are refused before allocating",
          "[io][limits]") {
    TempDir dir("limits-img");
    ngi::write_exr(dir / "a.exr", ngi::Image(4, 4, 3, 0.5f));
    const std::string exr = ngi::test::slurp(dir / "a.exr");
    // Data and display window of 1e9 x 1e9 pixels in a file of a few hundred bytes.
    std::string big = exr;
    for (const char* attr : {"dataWindow", "displayWindow"}) {
        const std::size_t at = big.find(std::string(attr) + std::string("\0box2i\0", 7));
        REQUIRE(at != std::string::npos);
        const std::size_t v = at + std::strlen(attr) + 7 + 4;
        const std::int32_t box[4] = {0, 0, 999999999, 999999999};
        std::memcpy(big.data() + v, box, 16);
    }
    CHECK_THROWS_WITH(ngi::detail::decode_exr(big, "big.exr"), Contains("big.exr") && Contains("data window"));
    // Only the display window huge (found by fuzz_exr): the data is 4x4, the image would be 5.6 GB of zeros.
    std::string display = exr;
    const std::size_t at = display.find(std::string("displayWindow\0box2i\0", 20));
    REQUIRE(at != std::string::npos);
    const std::int32_t box[4] = {0, 0, 40000, 40000};
    std::memcpy(display.data() + at + 20 + 4, box, 16);
    CHECK_THROWS_WITH(ngi::detail::decode_exr(display, "display.exr"),
                      Contains("display.exr") && Contains("display window 40001x40001"));
    // An attribute claiming 2 GiB: OpenEXR would allocate it before reading it.
    std::string attr = exr.substr(0, 8) + std::string("junk\0opaque\0", 12) + std::string("\xff\xff\xff\x7f", 4);
    CHECK_THROWS_WITH(ngi::detail::decode_exr(attr, "attr.exr"), Contains("attr.exr") && Contains("'junk' claims"));
    CHECK(ngi::detail::decode_exr(exr, "a.exr").width == 4);
    // Tiled, 1x1 tiles, the widest possible data window: 2^32 x 2^32 tiles used to be counted before the size check
    // (a signed overflow, caught by -DNGI_SANITIZE=ON builds).
    std::string tiled = big;
    tiled[5] = char(tiled[5] | 0x02);  // version flag 0x200: single-part tiled
    tiled.insert(8, std::string("tiles\0tiledesc\0\x09\0\0\0\x01\0\0\0\x01\0\0\0\0", 28));
    const std::size_t dw_at = tiled.find(std::string("dataWindow\0box2i\0", 17)) + 17 + 4;
    const std::int32_t widest[4] = {INT32_MIN, INT32_MIN, INT32_MAX, INT32_MAX};
    std::memcpy(tiled.data() + dw_at, widest, 16);
    CHECK_THROWS_WITH(ngi::detail::decode_exr(tiled, "tiled.exr"), Contains("tiled.exr") && Contains("data window"));
    // Huge tiles around a 4x4 data window (found by fuzz_exr): OpenEXR allocated a 3 GB tile buffer up front.
    std::string huge_tiles = exr;
    huge_tiles[5] = char(huge_tiles[5] | 0x02);
    huge_tiles.insert(8, std::string("tiles\0tiledesc\0\x09\0\0\0\0\0\x10\0\0\x04\0\0\0", 28));
    CHECK_THROWS_WITH(ngi::detail::decode_exr(huge_tiles, "tiles.exr"), Contains("tiles.exr") && Contains("tiles of"));
    // A chlist whose declared size disagrees with its entries (found by fuzz_exr): OpenEXR reads the entries and
    // went on to a 64379x257 data window of 12 channels the header walk had not seen (800 MB for a 572-byte file).
    std::string chlist = exr;
    const std::size_t ch_at = chlist.find(std::string("channels\0chlist\0", 16)) + 16;
    std::int32_t ch_size = 0;
    std::memcpy(&ch_size, chlist.data() + ch_at, 4);
    ch_size += 5;
    std::memcpy(chlist.data() + ch_at, &ch_size, 4);
    CHECK_THROWS_WITH(ngi::detail::decode_exr(chlist, "chlist.exr"),
                      Contains("chlist.exr") && Contains("'channels' of type chlist does not fill"));
    std::string short_box = exr;  // a box2i claiming 12 bytes: OpenEXR reads 16 regardless
    const std::size_t box_at = short_box.find(std::string("dataWindow\0box2i\0", 17)) + 17;
    short_box[box_at] = 12;
    CHECK_THROWS_WITH(ngi::detail::decode_exr(short_box, "box.exr"), Contains("'dataWindow' of type box2i"));

    ngi::write_png(dir / "a.png", ngi::Image(4, 4, 4, 0.5f));
    std::string png = ngi::test::slurp(dir / "a.png");
    // IHDR: length(4) "IHDR" width height ...; 30000 x 30000 RGBA = 3.6 GB of rows from a ~100-byte file.
    put_be32(png, 16, 30000);
    put_be32(png, 20, 30000);
    put_be32(png, 29, crc32(png.substr(12, 17)));
    CHECK_THROWS_WITH(ngi::detail::decode_png(png, "big.png"), Contains("big.png") && Contains("larger than the file"));
}

TEST_CASE("camera.json: values beyond float range are refused, not converted to inf", "[io][limits]") {
    glm::vec3 look, up;
    CHECK_THROWS_WITH(ngi::detail::decode_camera_json(R"({"look": [0, 0, -1e300], "up": [0, 1, 0]})", "cam.json",
                                                      look, up),
                      Contains("cam.json") && Contains("\"look\"") && Contains("finite"));
    ngi::detail::decode_camera_json(R"({"look": [0, 0, -1], "up": [0, 1, 0]})", "cam.json", look, up);
    CHECK(look.z == -1.0f);
}
