// Issue 31 ("Reliability, round two"): the reproducers of a hostile-user probe, each now a clear InputError (or a
// correct result) instead of a hang, a silent NaN, a black light or a lenient parse. docs/RELIABILITY.md lists them.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <climits>
#include <cstdlib>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <future>
#include <nlohmann/json.hpp>
#include <string>

#include "base/file_util.hpp"
#include "io_test_support.hpp"
#include "test_support.hpp"
#include "models/safetensors.hpp"
#include "models/family.hpp"
#include "ngi/area_light.hpp"
#include "ngi/dataset.hpp"
#include "ngi/device_buffer.hpp"
#include "ngi/error.hpp"
#include "ngi/host_memory.hpp"
#include "ngi/image_io.hpp"
#include "ngi/mesh.hpp"
#include "ngi/metrics.hpp"
#include "ngi/output_folder.hpp"
#include "ngi/scene.hpp"
#include "ngi/tensor.hpp"
#include "vox_writer.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using ngi::test::TempDir;

namespace {

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

std::string safetensors(const std::string& header_json, const std::string& data) {
    std::string b(8, '\0');
    for (int i = 0; i < 8; ++i) b[i] = char((std::uint64_t(header_json.size()) >> (8 * i)) & 0xff);
    return b + header_json + data;
}

std::string config_error(const nlohmann::json& config) {
    try {
        ngi::detail::parse_model_config(config.dump(), "m.safetensors");
    } catch (const ngi::InputError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST_CASE("round 2: a FIFO where a file is expected is refused at once by every reader", "[io][limits][reliability2]") {
    TempDir dir("r2-fifo");
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

TEST_CASE("round 2: every float field of a model config must survive float32", "[model][limits][reliability2]") {
    const nlohmann::json unet = {{"family", "pix2pix_unet"}, {"input_nc", 12}, {"output_nc", 3}, {"ngf", 8},
                                 {"num_downs", 6}, {"bn_eps", 1e-5}, {"leaky_slope", 0.2}, {"dropout_p", 0.5},
                                 {"input_range", {-1, 1}}, {"output_range", {-1, 1}}};
    REQUIRE(config_error(unet).empty());
    // bn_eps 1e-300 passed "(0, 1]" as a double and was 0 in float32: an all-zero input gave 49,152 NaN outputs.
    for (const auto& [key, value] : std::vector<std::pair<std::string, nlohmann::json>>{
             {"bn_eps", 1e-300}, {"bn_eps", 1e-40}, {"leaky_slope", 1e-300}, {"dropout_p", 1e-45},
             {"input_range", {1e-300, 2e-300}}, {"output_range", {-1e-39, 1e-39}}}) {
        nlohmann::json c = unet;
        c[key] = value;
        INFO(key << " = " << value.dump());
        CHECK_THAT(config_error(c),
                   Contains("m.safetensors") && Contains("'" + key + "'") && Contains("representable in float32"));
    }
    nlohmann::json ok = unet;
    ok["bn_eps"] = 1.2e-38;  // a normal float: kept
    ok["leaky_slope"] = 0.0;  // zero is exact
    CHECK(config_error(ok).empty());

    // The other families: an MLP layer's slope, neural_gi's scene box, voxel_sh's statistics.
    const nlohmann::json mlp = {{"family", "mlp"}, {"input_nc", 3},
                                {"layers", {{{"out", 1}, {"activation", "leaky_relu"}, {"slope", 0.1}}}}};
    REQUIRE(config_error(mlp).empty());
    nlohmann::json bad = mlp;
    bad["layers"][0]["slope"] = 1e-300;
    CHECK_THAT(config_error(bad), Contains("layers[0].slope") && Contains("float32"));

    const nlohmann::json neural = {
        {"family", "neural_gi"}, {"input_nc", 18}, {"output_nc", 3}, {"ngf", 8}, {"num_downs", 5},
        {"dropout", "off"},
        {"neural_gi", {{"buffer_channels", 4}, {"mlp_width", 8}, {"mlp_depth", 2}, {"skip_layer", 1}, {"decode", "exp"},
                       {"scene_box", {{"min", {0, 0, 0}}, {"max", {8, 8, 8}}}}}}};
    REQUIRE(config_error(neural).empty());
    bad = neural;
    bad["neural_gi"]["scene_box"]["min"] = {1e-300, 0, 0};
    CHECK_THAT(config_error(bad), Contains("neural_gi.scene_box") && Contains("float32"));

    nlohmann::json voxel = {{"family", "voxel_sh"}, {"architecture", "mlp"}, {"grid", {4, 4, 4}}, {"hidden", {8}},
                            {"input_lo", std::vector<double>(10, 0.0)}, {"input_hi", std::vector<double>(10, 1.0)},
                            {"output_mean", std::vector<double>(27, 0.0)}, {"output_std", std::vector<double>(27, 1.0)}};
    REQUIRE(config_error(voxel).empty());
    voxel["output_std"][3] = 1e-300;  // would be 0 in float32: every output the mean
    CHECK_THAT(config_error(voxel), Contains("output_std") && Contains("float32"));
}

TEST_CASE("round 2: .vox emission that overflows after the flux scaling is refused", "[vox][render][reliability2]") {
    using namespace vox_test;
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
    TempDir dir("r2-emission");
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

TEST_CASE("round 2: safetensors with trailing bytes or a NUL-padded header are refused", "[model][limits][reliability2]") {
    const std::string header = R"({"w": {"dtype": "F32", "shape": [2], "data_offsets": [0, 8]}})";
    const std::string data(8, '\0');
    REQUIRE(ngi::detail::parse_safetensors(safetensors(header, data), "ok").tensors.size() == 1);
    // Space padding is the format's own: accepted.
    REQUIRE(ngi::detail::parse_safetensors(safetensors(header + "    ", data), "ok").tensors.size() == 1);
    CHECK_THROWS_WITH(ngi::detail::parse_safetensors(safetensors(header, data + "junk"), "tail.safetensors"),
                      Contains("tail.safetensors") && Contains("4 trailing bytes after the last tensor"));
    CHECK_THROWS_WITH(ngi::detail::parse_safetensors(safetensors(header + std::string(6, '\0'), data), "nul.safetensors"),
                      Contains("nul.safetensors") && Contains("NUL byte"));
    // A header of only metadata holds no data: any byte after it is trailing.
    CHECK_THROWS_WITH(ngi::detail::parse_safetensors(safetensors(R"({"__metadata__": {}})", "x"), "meta"),
                      Contains("1 trailing bytes"));
}

TEST_CASE("round 2: dataset configs refuse duplicate keys and backwards time ranges", "[render][dataset][reliability2]") {
    const std::string train = R"("train": [{"scene": "room:seed=1"}])";
    REQUIRE_NOTHROW(ngi::DatasetConfig::parse("{\"n\": 8, " + train + "}", "/tmp/c.json"));
    // nlohmann keeps the last of two equal keys silently: {"n": 64, "n": 8} rendered at 8.
    CHECK_THROWS_WITH(ngi::DatasetConfig::parse("{\"n\": 64, \"n\": 8, " + train + "}", "/tmp/c.json"),
                      Contains("/tmp/c.json") && Contains("duplicate key 'n'"));
    CHECK_THROWS_WITH(ngi::DatasetConfig::parse(R"({"train": [{"scene": "room:seed=1", "frames": 2, "frames": 3}]})",
                                                "/tmp/c.json"),
                      Contains("duplicate key 'frames'"));
    // Equal keys in different objects are fine.
    CHECK_NOTHROW(ngi::DatasetConfig::parse(
        R"({"train": [{"scene": "room:seed=1", "frames": 2}], "test": [{"scene": "room:seed=2", "frames": 2}]})",
        "/tmp/c.json"));
    // A time range runs forward; hours go to 48 so that a night crosses midnight forward.
    CHECK_THROWS_WITH(ngi::DatasetConfig::parse(R"({"train": [{"scene": "room:seed=1", "time": [20, 10]}]})",
                                                "/tmp/c.json"),
                      Contains("train[0]") && Contains("end is before the start"));
    CHECK_NOTHROW(ngi::DatasetConfig::parse(R"({"train": [{"scene": "room:seed=1", "time": [22, 26]}]})", "/tmp/c.json"));
    CHECK_NOTHROW(ngi::DatasetConfig::parse(R"({"train": [{"scene": "room:seed=1", "time": [12, 12]}]})", "/tmp/c.json"));
    // Model metadata too.
    REQUIRE(config_error(nlohmann::json::parse(R"({"family": "mlp", "input_nc": 3, "layers": [{"out": 1}]})")).empty());
    CHECK_THROWS_WITH(ngi::detail::parse_model_config(
                          R"({"family": "mlp", "input_nc": 3, "input_nc": 4, "layers": [{"out": 1}]})", "dup.safetensors"),
                      Contains("dup.safetensors") && Contains("duplicate key 'input_nc'"));
}

TEST_CASE("round 2: a .vox nTRN frame count beyond its bytes is refused", "[vox][reliability2]") {
    using namespace vox_test;
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

TEST_CASE("round 2: OutputFolder::commit_all puts every folder in place or none", "[io][output][reliability2]") {
    TempDir dir("r2-commit");
    fs::create_directories(dir / "a");
    ngi::test::spit(dir / "a/x.txt", "old a");
    {  // Both staged; then b's target gains a foreign file, so b cannot be committed: a must stay as it was.
        ngi::OutputFolder a(dir / "a", "write", std::vector<std::string>{"x.txt"});
        ngi::OutputFolder b(dir / "b", "write", std::vector<std::string>{"y.txt"});
        a.write_text("x.txt", "new a");
        b.write_text("y.txt", "new b");
        fs::create_directories(dir / "b");
        ngi::test::spit(dir / "b/foreign.txt", "not ours");
        CHECK_THROWS_WITH(ngi::OutputFolder::commit_all({&a, &b}), Contains("foreign.txt"));
    }
    CHECK(ngi::test::slurp(dir / "a/x.txt") == "old a");
    CHECK(ngi::test::slurp(dir / "b/foreign.txt") == "not ours");
    CHECK(!fs::exists(dir / "b/y.txt"));
    CHECK(dir.list() == std::vector<std::string>{"a", "b"});  // no staging or .old folder left
    fs::remove_all(dir / "b");
    {  // Now both commit.
        ngi::OutputFolder a(dir / "a", "write", std::vector<std::string>{"x.txt"});
        ngi::OutputFolder b(dir / "b", "write", std::vector<std::string>{"y.txt"});
        a.write_text("x.txt", "new a");
        b.write_text("y.txt", "new b");
        ngi::OutputFolder::commit_all({&a, &b});
    }
    CHECK(ngi::test::slurp(dir / "a/x.txt") == "new a");
    CHECK(ngi::test::slurp(dir / "b/y.txt") == "new b");
    CHECK(dir.list() == std::vector<std::string>{"a", "b"});
}

TEST_CASE("round 2: output names up to NAME_MAX work: staging names are shortened to fit", "[io][output][reliability2]") {
    TempDir dir("r2-names");
    for (std::size_t len : {std::size_t(240), std::size_t(241), std::size_t(250), std::size_t(NAME_MAX)}) {
        INFO(len);
        const std::string name(len, 'n');
        const std::string tmp = ngi::detail::temp_name(dir / name);
        CHECK(fs::path(tmp).filename().string().size() <= std::size_t(NAME_MAX));
        CHECK(tmp.find(".tmp-") != std::string::npos);
        // A folder (the staging folder and the .old name of a re-run) and a single file (write_file_atomic).
        for (int run = 0; run < 2; ++run) {
            ngi::OutputFolder f(dir / name, "write", std::vector<std::string>{"a.txt"});
            f.write_text("a.txt", "run " + std::to_string(run));
            f.commit();
        }
        CHECK(ngi::test::slurp(dir / name + "/a.txt") == "run 1");
        fs::remove_all(dir / name);
        ngi::detail::write_file_atomic(dir / name, "file");
        CHECK(ngi::test::slurp(dir / name) == "file");
        fs::remove(dir / name);
    }
    CHECK(dir.list().empty());
    // A long name of multi-byte characters is cut at a character boundary.
    std::string wide;
    while (wide.size() + 2 <= 254) wide += "\xc3\xa9";  // U+00E9, two bytes
    const std::string cut = fs::path(ngi::detail::temp_name(dir / wide)).filename().string();
    const std::string stem = cut.substr(0, cut.find(".tmp-"));
    CHECK(stem.size() % 2 == 0);
    CHECK(cut.size() <= std::size_t(NAME_MAX));
}

TEST_CASE("round 2: metrics refuse a data range whose SSIM constants are not float32 numbers", "[metrics][reliability2]") {
    // --range 1e38 gave "ssim": null with an empty note (C1 = (0.01 R)^2 was Inf in the kernel); --range 1e-45 gave
    // PSNR -892 dB. A positive range must lie in [1e-15, 1e15], the bound the values themselves have.
    auto& dev = ngi::test::device();
    ngi::Image a(16, 16, 1), b(16, 16, 1);
    for (std::size_t i = 0; i < a.data.size(); ++i) {
        a.data[i] = float(i % 5) * 0.1f;
        b.data[i] = float(i % 3) * 0.1f;
    }
    for (double r : {1e38, 1e16, 1e-16, 1e-45}) {
        INFO(r);
        // compare_images (what ngi lightmap scores with) reports them undefined, saying why; ssim() refuses them.
        const ngi::ImageMetrics m = ngi::compare_images(dev, a, b, r);
        CHECK(std::isnan(m.psnr));
        CHECK(std::isnan(m.ssim));
        CHECK_THAT(m.psnr_note, Contains("is outside [1e-15, 1e15]") && Contains("PSNR is not reported"));
        CHECK_THAT(m.ssim_note, Contains("is outside [1e-15, 1e15]") && Contains("SSIM is not reported"));
        CHECK_THROWS_WITH(ngi::ssim(dev, a, b, r), Contains("data_range must be in [1e-15, 1e15]"));
        const ngi::ImageMetrics same = ngi::compare_images(dev, a, a, r);  // identical images: as for every range
        CHECK(std::isinf(same.psnr));
        CHECK(same.ssim == 1.0);
    }
    for (double r : {1e15, 1e-15, 1.0}) {
        INFO(r);
        const ngi::ImageMetrics m = ngi::compare_images(dev, a, b, r);
        CHECK(std::isfinite(m.psnr));
        CHECK(std::isfinite(m.ssim));
    }
}

// Item 6 of round 2: a valid 14 KB scene padded to a 3 GiB sparse .vox was read whole (38 s, 4 GB RSS, exit 0).
TEST_CASE("round 2: a .vox file beyond kMaxVoxFileBytes is refused before it is read", "[vox][limits][reliability2]") {
    using namespace vox_test;
    TempDir dir("r2-vox-size");
    const fs::path path = dir / "padded.vox";
    ngi::test::spit(path, vox_file(size_chunk(1, 1, 1) + xyzi({{0, 0, 0, 7}})));
    CHECK(ngi::load_vox(path.string()).palette.size() > 1);  // valid as written
    fs::resize_file(path, ngi::kMaxVoxFileBytes + 1);           // sparse: no disk space, no memory
    // Refused from the size fstat reports (the message quotes it), before any byte is read.
    CHECK_THROWS_WITH(ngi::load_vox(path.string()),
                      Contains("padded.vox") && Contains("is larger (" + std::to_string(ngi::kMaxVoxFileBytes + 1)));
}

namespace {

// Sets the process's host-memory limit for one scope (ngi/host_memory.hpp) and restores the default after.
struct HostMemoryLimit {
    explicit HostMemoryLimit(std::uint64_t bytes) { ngi::set_host_memory_limit(bytes); }
    ~HostMemoryLimit() { ngi::set_host_memory_limit(0); }
    HostMemoryLimit(const HostMemoryLimit&) = delete;
    HostMemoryLimit& operator=(const HostMemoryLimit&) = delete;
};

}  // namespace

// Round three (issue 51): the viewer at --n 2048 reached 15 GB past NGI_HOST_MEMORY_LIMIT -- its network's tensor
// arena, allocated on PoCL, whose device memory is host memory. ngi's buffers on a CPU device now count against the
// budget while they live.
TEST_CASE("round 3: ngi's buffers on a CPU device count against the host-memory budget while they live",
          "[io][limits][reliability2]") {
    ngi::Device& dev = ngi::test::device();
    if (!dev.info().is_cpu) {
        WARN("not a CPU device: its memory is not host memory, nothing to check");
        return;
    }
    const HostMemoryLimit limit(256u << 20);  // other buffers of this process (a test device's) hold far less
    const std::uint64_t before = ngi::host_memory_held();
    CHECK_THROWS_WITH(ngi::DeviceBuffer::allocate(dev, 257u << 20),
                      Contains("allocate device buffer on a CPU device") && Contains("needs 269484032 bytes") &&
                          Contains("host-memory limit"));
    CHECK(ngi::host_memory_held() == before);  // a refusal holds nothing
    {
        const ngi::DeviceBuffer a = ngi::DeviceBuffer::allocate(dev, 160u << 20);
        CHECK(ngi::host_memory_held() == before + (160u << 20));
        // 160 MiB held: 160 more would pass the 256 MiB budget.
        CHECK_THROWS_WITH(ngi::DeviceBuffer::allocate(dev, 160u << 20), Contains("already held"));
        CHECK_NOTHROW(ngi::DeviceBuffer::allocate(dev, 64u << 20));
    }
    // Released: the budget is free again.
    CHECK(ngi::host_memory_held() == before);
    CHECK_NOTHROW(ngi::DeviceBuffer::allocate(dev, 200u << 20));
}

// The same ledger holds what an application or the pipeline keeps on the host (the GL viewer's G-buffer on a
// software renderer, the global view's tables): a HostMemoryHold and a CPU device's buffers are judged together.
TEST_CASE("round 3: host-memory holds and CPU device buffers share one ledger", "[io][limits][reliability2]") {
    ngi::Device& dev = ngi::test::device();  // opened first: what it holds is part of `before`
    const std::uint64_t before = ngi::host_memory_held();  // whatever this process already holds, plus 256 MiB
    const HostMemoryLimit limit(before + (256u << 20));
    CHECK_THROWS_WITH(ngi::HostMemoryHold("the test's frames", 300u << 20),
                      Contains("the test's frames: needs 314572800 bytes") && Contains("host-memory limit"));
    CHECK(ngi::host_memory_held() == before);
    {
        ngi::HostMemoryHold frames("the test's frames", 160u << 20);
        CHECK(ngi::host_memory_held() == before + (160u << 20));
        CHECK_THROWS_WITH(ngi::HostMemoryHold("more frames", 160u << 20), Contains("already held"));
        if (dev.info().is_cpu)
            CHECK_THROWS_WITH(ngi::DeviceBuffer::allocate(dev, 160u << 20), Contains("already held"));
        ngi::HostMemoryHold moved = std::move(frames);  // the hold moves; it is released once
        CHECK(frames.bytes() == 0);
        CHECK(moved.bytes() == (160u << 20));
        CHECK(ngi::host_memory_held() == before + (160u << 20));
        moved = ngi::HostMemoryHold("smaller frames", 32u << 20);  // assignment releases the old hold
        CHECK(ngi::host_memory_held() == before + (32u << 20));
    }
    CHECK(ngi::host_memory_held() == before);
}

// Item 6 of round 2: an 805 MB npy into an AO model reached 2.5 GB of host memory unchecked. Every reader now
// checks what it will hold at once -- the file's bytes plus what they decode to -- against a limit the user can
// raise (NGI_HOST_MEMORY_LIMIT), before allocating. A compressed image is judged by its decoded size, not its file.
TEST_CASE("round 2: readers check the host memory they will hold before allocating", "[io][limits][reliability2]") {
    TempDir dir("r2-host-memory");
    // 512 x 512 x 3 constant: small files (ZIP / deflate), 3 MiB of floats once decoded.
    ngi::Image flat(512, 512, 3, 0.25f);
    const std::string exr = dir / "flat.exr", png = dir / "flat.png", npy = dir / "flat.npy";
    ngi::write_exr(exr, flat, ngi::ExrPixelType::Half);
    ngi::write_png(png, flat);
    ngi::Tensor t({3, 512, 512});
    ngi::write_npy(npy, t);
    REQUIRE(fs::file_size(exr) < 64 * 1024);
    REQUIRE(fs::file_size(png) < 64 * 1024);
    {
        HostMemoryLimit limit(1 << 20);  // 1 MiB: every decoded image above is 3 MiB
        for (const std::string& path : {exr, png, npy}) {
            INFO(path);
            CHECK_THROWS_WITH(path.ends_with(".npy") ? void(ngi::read_npy(path)) : void(ngi::read_image(path)),
                              Contains(path) && Contains("of host memory at once") &&
                                  Contains("host-memory limit of 1048576 bytes (1 MiB)") &&
                                  Contains("NGI_HOST_MEMORY_LIMIT"));
        }
        // The file itself over the limit: refused from its size, before a byte is read.
        HostMemoryLimit tiny(1000);
        CHECK_THROWS_WITH(ngi::detail::read_file(npy, "read"), Contains("flat.npy") && Contains("1000 bytes"));
    }
    // The default limit (half the physical memory, at least 1 GiB) reads them all.
    CHECK(ngi::host_memory_limit() >= (std::uint64_t(1) << 30));
    CHECK(ngi::read_image(exr).data.size() == flat.data.size());
    CHECK(ngi::read_image(png).data.size() == flat.data.size());
    CHECK(ngi::read_npy(npy).data.size() == flat.data.size());
    // Exactly at the limit is allowed: the npy holds its 3 MiB of values plus its file's bytes.
    {
        HostMemoryLimit exact(fs::file_size(npy) + 512 * 512 * 3 * sizeof(float));
        CHECK(ngi::read_npy(npy).data.size() == flat.data.size());
        HostMemoryLimit one_less(fs::file_size(npy) + 512 * 512 * 3 * sizeof(float) - 1);
        CHECK_THROWS_AS(ngi::read_npy(npy), ngi::InputError);
    }
}

TEST_CASE("round 2: NGI_HOST_MEMORY_LIMIT takes bytes with a binary suffix, and names itself when malformed",
          "[io][limits][reliability2]") {
    const char* old = std::getenv("NGI_HOST_MEMORY_LIMIT");
    const std::string saved = old ? old : "";
    auto with_env = [](const char* value) {
        ::setenv("NGI_HOST_MEMORY_LIMIT", value, 1);
        return ngi::host_memory_limit();
    };
    CHECK(with_env("123456") == 123456u);
    CHECK(with_env("64K") == 64u << 10);
    CHECK(with_env("512m") == 512u << 20);
    CHECK(with_env("16G") == std::uint64_t(16) << 30);
    CHECK(with_env("2T") == std::uint64_t(2) << 40);
    for (const char* bad : {"lots", "0", "-5", "12GB", "1.5G", "99999999999999999999", "20000000T"}) {
        INFO(bad);
        CHECK_THROWS_WITH(with_env(bad), Contains(std::string("NGI_HOST_MEMORY_LIMIT='") + bad + "'"));
    }
    {
        HostMemoryLimit set(4096);  // the application's setting wins over the environment
        CHECK(with_env("lots") == 4096u);
    }
    if (old) ::setenv("NGI_HOST_MEMORY_LIMIT", saved.c_str(), 1);
    else ::unsetenv("NGI_HOST_MEMORY_LIMIT");
    CHECK(ngi::host_memory_limit() >= (std::uint64_t(1) << 30));
    CHECK(ngi::describe_bytes(805306368) == "805306368 bytes (768 MiB)");
    CHECK(ngi::describe_bytes(3u << 30) == "3221225472 bytes (3.0 GiB)");
    CHECK(ngi::describe_bytes(1000) == "1000 bytes");
}
