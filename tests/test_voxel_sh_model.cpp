// Seed 004's voxel_sh model family (models/voxel_sh_model.*): whole model files against PyTorch (the oracle:
// tests/parity/make_voxel_sh_parity.py runs ngi.voxel_sh in float64), the input guard, broken
// files, and the ops the runner added (planar set pooling, the per-channel affine, the residual add) against
// straight double-precision loops.
#include <catch2/catch.hpp>
#include <cfloat>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>

#include "ngi/device_buffer.hpp"
#include "ngi/error.hpp"
#include "ngi/tensor.hpp"
#include "ngi/model.hpp"
#include "ops/elementwise.hpp"
#include "ops/set_pool.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// [V, C] -> [C, V] and back.
std::vector<float> transpose(const std::vector<float>& a, int rows, int cols) {
    std::vector<float> t(a.size());
    for (int r = 0; r < rows; ++r)
        for (int c = 0; c < cols; ++c) t[std::size_t(c) * rows + r] = a[std::size_t(r) * cols + c];
    return t;
}

const fs::path& parity_dir() {
    static const fs::path dir = ngi::test::python_oracle_data("make_voxel_sh_parity.py", "voxel_sh_parity");
    return dir;
}

nlohmann::json parity_cases() {
    nlohmann::json cases;
    std::ifstream(parity_dir() / "cases.json") >> cases;
    return cases;
}

// Every parity case of one architecture: F32 and F16 weights, V = 1, 37, 1001; V = 37 also device in, device out.
void check_parity(const std::string& arch) {
    const auto t0 = std::chrono::steady_clock::now();
    const nlohmann::json cases = parity_cases();
    REQUIRE(cases.size() == 18);
    std::map<std::string, double> worst_abs;  // per model file
    std::map<std::string, std::unique_ptr<ngi::Model>> models;
    std::map<std::string, std::pair<ngi::Tensor, ngi::Tensor>> one_voxel;  // per model: V = 1's input and output
    int checked = 0;
    for (const auto& c : cases) {
        if (c["architecture"] != arch) continue;
        const std::string name = c["name"], model = c["model"];
        CAPTURE(name);
        auto& m = models[model];
        if (!m) {
            m = std::make_unique<ngi::Model>(ngi::Model::load(ngi::test::device(), (parity_dir() / model).string()));
            const ngi::ModelConfig& cfg = m->config();
            CHECK(cfg.family == "voxel_sh");
            CHECK(cfg.voxel_sh.architecture == arch);
            CHECK((cfg.voxel_sh.grid[0] == 32 && cfg.voxel_sh.grid[1] == 32 && cfg.voxel_sh.grid[2] == 32));
            CHECK(cfg.input_nc == 10);
            CHECK(cfg.output_nc == 27);
        }
        const ngi::Tensor x = ngi::read_npy((parity_dir() / c["input"].get<std::string>()).string());
        const ngi::Tensor want = ngi::read_npy((parity_dir() / c["expected"].get<std::string>()).string());
        ngi::RunInfo info;
        const ngi::Tensor y = m->run(x, &info);
        REQUIRE(y.shape == want.shape);
        CHECK(info.sanitized_inputs == 0);
        // float32 against float64 on the same stored weights. The dense layers are sums of <= 256 products of
        // O(1) terms through tanh (rounding ~1e-7 relative per layer); the resnet adds 10 residual blocks into
        // one running sum (|h| up to ~10); the output is de-standardized by std <= 2. Observed max |diff| on PoCL
        // and rusticl: <= 1.0e-6 for mlp and set, <= 6.7e-6 for the resnet (|y| up to 10; WARN below prints
        // it). 1e-4 absolute + 1e-4 relative: an order of magnitude of room for other devices' tanh, far below
        // an error that would matter (the coefficients' std is ~1) and far below what a wrong layer gives (~0.1).
        REQUIRE(ngi::test::worst_ratio(y.data, want.data, 1e-4, 1e-4) <= 1.0);
        worst_abs[model] = std::max(worst_abs[model], ngi::test::max_abs_diff(y.data, want.data));
        ++checked;
        if (c["voxels"].get<int>() == 1) one_voxel[model] = {x, y};

        // Device in, device out (planar [10, V] -> [27, V]) computes the same, bit for bit.
        if (c["voxels"].get<int>() == 37) {
            const int v = 37;
            const std::vector<float> planar_in = transpose(x.data, v, 10);
            ngi::DeviceBuffer in = ngi::DeviceBuffer::allocate(ngi::test::device(), planar_in.size() * sizeof(float));
            ngi::DeviceBuffer out = ngi::DeviceBuffer::allocate(ngi::test::device(), 27 * v * sizeof(float));
            in.upload(planar_in.data(), planar_in.size() * sizeof(float));
            m->enqueue(in, out, 1, v);
            std::vector<float> planar_out(27 * v);
            out.download(planar_out.data(), planar_out.size() * sizeof(float));
            CHECK(transpose(planar_out, 27, v) == y.data);
            CHECK(m->sanitized_inputs() == 0);
        }
    }
    CHECK(checked == 6);
    // Fewer items than a GEMM tile after a run of many (the buffers only grow): the same result again. Each layer
    // then copies its items into zero-padded rows in scratch that the larger run sized.
    for (const auto& [model, xy] : one_voxel) {
        CAPTURE(model);
        CHECK(models[model]->run(xy.first).data == xy.second.data);
    }
    CHECK(one_voxel.size() == 2);
    for (const auto& [model, e] : worst_abs) WARN("voxel_sh parity " << model << ": max |ngi - PyTorch float64| " << e);
    WARN("voxel_sh parity " << arch << ": " << checked << " cases in " << seconds_since(t0) << " s");
}

}  // namespace

TEST_CASE("voxel_sh mlp files match PyTorch (F32 and F16 weights, V = 1, 37, 1001)", "[voxel_sh][model][parity]") {
    check_parity("mlp");
}

TEST_CASE("voxel_sh set network files match PyTorch's broadcast concat (F32 and F16, V = 1, 37, 1001)",
          "[voxel_sh][model][parity]") {
    check_parity("set");
}

TEST_CASE("voxel_sh resnet files match PyTorch (F32 and F16 weights, V = 1, 37, 1001)", "[voxel_sh][model][parity]") {
    check_parity("resnet");
}

TEST_CASE("voxel_sh input guard: NaN -> the middle of the training range, counted, +-FLT_MAX and +-Inf stay finite",
          "[voxel_sh][model]") {
    for (const char* arch : {"set", "resnet"}) {
        CAPTURE(arch);
        ngi::Model m =
            ngi::Model::load(ngi::test::device(), (parity_dir() / (std::string(arch) + "_f32.safetensors")).string());
        const auto& vs = m.config().voxel_sh;
        const ngi::Tensor x = ngi::read_npy((parity_dir() / (std::string(arch) + "_f32_v37_input.npy")).string());
        const int v = x.shape[0];

        // NaN in three places (the constant channel 8 included): the same as the raw midpoint (lo + hi) / 2,
        // which standardizes to 0 (up to the rounding of s x + t).
        ngi::Tensor bad = x, mid = x;
        const std::pair<int, int> spots[] = {{0, 0}, {5, 9}, {v - 1, 8}};
        for (auto [i, c] : spots) {
            bad.data[std::size_t(i) * 10 + c] = NAN;
            mid.data[std::size_t(i) * 10 + c] = float(0.5 * (vs.input_lo[c] + vs.input_hi[c]));
        }
        ngi::RunInfo info;
        const ngi::Tensor y_bad = m.run(bad, &info);
        CHECK(info.sanitized_inputs == 3);
        const ngi::Tensor y_mid = m.run(mid, &info);
        CHECK(info.sanitized_inputs == 0);
        CHECK(ngi::test::max_abs_diff(y_bad.data, y_mid.data) < 1e-4);

        // Huge and infinite values: standardized beyond 1e6 -> +-1e6 (counted), so FLT_MAX and +Inf give the same
        // finite output; an Inf in the constant channel (scale 0: 0 * Inf = NaN) becomes 0.
        ngi::Tensor huge = x, inf = x;
        const std::pair<int, float> values[] = {{3, FLT_MAX}, {14, -FLT_MAX}, {25, 3e38f}};
        for (auto [i, value] : values) {
            huge.data[std::size_t(i) * 10 + 1] = value;
            inf.data[std::size_t(i) * 10 + 1] = value > 0 ? INFINITY : -INFINITY;
        }
        huge.data[std::size_t(7) * 10 + 8] = INFINITY;
        inf.data[std::size_t(7) * 10 + 8] = -INFINITY;
        const ngi::Tensor y_huge = m.run(huge, &info);
        CHECK(info.sanitized_inputs == 4);
        CHECK(ngi::test::all_finite(y_huge.data));
        const ngi::Tensor y_inf = m.run(inf, &info);
        CHECK(info.sanitized_inputs == 4);
        CHECK(y_inf.data == y_huge.data);
    }
}

namespace {

struct Entry {
    std::string name;
    std::vector<int> shape;
    float value;
};

// A safetensors file from (name, shape, constant value) entries and a config.
std::string write_file(const std::string& stem, const std::vector<Entry>& entries, const nlohmann::json& config) {
    nlohmann::json header;
    std::string data;
    for (const auto& e : entries) {
        std::size_t n = 1;
        for (int d : e.shape) n *= std::size_t(d);
        std::vector<float> v(n, e.value);
        header[e.name] = {{"dtype", "F32"}, {"shape", e.shape}, {"data_offsets", {data.size(), data.size() + 4 * n}}};
        data.append(reinterpret_cast<const char*>(v.data()), 4 * n);
    }
    header["__metadata__"] = {{"ngi", config.dump()}};
    std::string h = header.dump();
    while (h.size() % 8) h += ' ';
    std::string bytes(8, '\0');
    const std::uint64_t len = h.size();
    for (int i = 0; i < 8; ++i) bytes[i] = char((len >> (8 * i)) & 0xff);
    bytes += h + data;
    const fs::path p = fs::temp_directory_path() / ("ngi_test_voxel_sh_" + stem + ".safetensors");
    std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    return p.string();
}

// A tiny resnet: width 4, one block.
nlohmann::json tiny_config() {
    return {{"family", "voxel_sh"}, {"architecture", "resnet"}, {"grid", {8, 4, 2}}, {"width", 4}, {"blocks", 1},
            {"input_lo", std::vector<double>(10, 0.0)}, {"input_hi", std::vector<double>(10, 1.0)},
            {"output_mean", std::vector<double>(27, 0.5)}, {"output_std", std::vector<double>(27, 2.0)}};
}

std::vector<Entry> tiny_entries() {
    return {{"input.weight", {4, 10}, 0.1f}, {"input.bias", {4}, 0.0f},  {"blocks.0.weight", {4, 4}, 0.2f},
            {"blocks.0.bias", {4}, 0.1f},    {"output.weight", {27, 4}, 0.3f}, {"output.bias", {27}, -0.1f}};
}

void expect_error(const std::string& path, const std::string& fragment) {
    INFO("file " << path);
    REQUIRE_THROWS_WITH(ngi::Model::load(ngi::test::device(), path), Contains(fragment));
}

}  // namespace

TEST_CASE("broken voxel_sh model files give clear errors naming the field or tensor", "[voxel_sh][model][file]") {
    const nlohmann::json cfg = tiny_config();
    const std::vector<Entry> ok = tiny_entries();
    {
        ngi::Model m = ngi::Model::load(ngi::test::device(), write_file("ok", ok, cfg));
        const auto& vs = m.config().voxel_sh;
        CHECK((vs.grid[0] == 8 && vs.grid[1] == 4 && vs.grid[2] == 2));
        CHECK(m.config().input_layout.size() == 10);
        // x' = 2 x - 1 with x = 0.5 everywhere: h = tanh(0) = 0, h += tanh(0.1) per unit, y = 2 (4 * 0.3 tanh(0.1)
        // - 0.1) + 0.5.
        ngi::Tensor x({5, 10});
        std::fill(x.data.begin(), x.data.end(), 0.5f);
        const ngi::Tensor y = m.run(x);
        REQUIRE(y.shape == std::vector<int>{5, 27});
        for (float v : y.data) CHECK(v == Approx(2 * (4 * 0.3 * std::tanh(0.1) - 0.1) + 0.5).epsilon(1e-5));
        REQUIRE_THROWS_WITH(m.run(ngi::Tensor({5, 9})), Contains("[V, 10]"));
        REQUIRE_THROWS_WITH(m.run(ngi::Tensor({1, 10, 1, 5})), Contains("[V, 10]"));
        REQUIRE_THROWS_WITH(vs.check_grid(32, 32, 32), Contains("32x32x32") && Contains("8x4x2"));
        CHECK_NOTHROW(vs.check_grid(8, 4, 2));
    }
    auto with = [&](const char* key, const nlohmann::json& value) {
        nlohmann::json c = cfg;
        if (value.is_null()) c.erase(key);
        else c[key] = value;
        return c;
    };
    const nlohmann::json none;  // with(key, none): the key removed
    expect_error(write_file("nogrid", ok, with("grid", none)), "field 'grid' must be [X, Y, Z]");
    expect_error(write_file("nogrid", ok, with("grid", none)), "(missing)");
    expect_error(write_file("grid2", ok, with("grid", {8, 4})), "field 'grid' must be");
    expect_error(write_file("gridbig", ok, with("grid", {4096, 4096, 2})), "field 'grid' must be");
    expect_error(write_file("lo9", ok, with("input_lo", std::vector<double>(9, 0.0))),
                 "field 'input_lo' must be a list of 10 finite numbers");
    expect_error(write_file("hilo", ok, with("input_hi", std::vector<double>(10, -1.0))),
                 "fields 'input_lo', 'input_hi': channel 0 has lo");
    expect_error(write_file("mean26", ok, with("output_mean", std::vector<double>(26, 0.0))), "field 'output_mean'");
    expect_error(write_file("stdneg", ok, with("output_std", std::vector<double>(27, -1.0))), "field 'output_std'");
    expect_error(write_file("arch", ok, with("architecture", "cnn")),
                 "field 'architecture' must be one of \"mlp\", \"set\", \"resnet\", got \"cnn\"");
    expect_error(write_file("noarch", ok, with("architecture", none)), "field 'architecture'");
    expect_error(write_file("width", ok, with("width", 0)), "field 'width' must be an integer in 1..4096");
    expect_error(write_file("stray", ok, with("hidden", {4})), "field 'hidden' does not belong to architecture");
    expect_error(write_file("innc", ok, with("input_nc", 12)), "field 'input_nc'");
    expect_error(write_file("required", ok, with("required", {"grid", "lighting"})), "lists 'lighting'");
    std::vector<Entry> bad = ok;
    bad[2].shape = {4, 5};
    expect_error(write_file("shape", bad, cfg), "tensor 'blocks.0.weight' is [4, 5], expected [4, 4]");
    bad = ok;
    bad.erase(bad.begin() + 5);
    expect_error(write_file("missing", bad, cfg), "tensor 'output.bias' is missing");
    bad = ok;
    bad.push_back({"blocks.1.weight", {4, 4}, 0.0f});
    expect_error(write_file("extra", bad, cfg), "tensor 'blocks.1.weight' is not part of this voxel_sh resnet");
    bad = ok;
    bad[1].value = NAN;
    expect_error(write_file("nan", bad, cfg), "tensor 'input.bias': value 0 is not finite");
    // The set network's first rho layer reads [h | max | mean]: three times phi's last width.
    const nlohmann::json set_cfg = [&] {
        nlohmann::json c = cfg;
        c.erase("width");
        c.erase("blocks");
        c["architecture"] = "set";
        c["phi"] = {3};
        c["rho"] = {5};
        return c;
    }();
    const std::vector<Entry> set_ok = {{"phi.0.weight", {3, 10}, 0.1f}, {"phi.0.bias", {3}, 0.0f},
                                       {"rho.0.weight", {5, 9}, 0.1f},  {"rho.0.bias", {5}, 0.0f},
                                       {"rho.1.weight", {27, 5}, 0.1f}, {"rho.1.bias", {27}, 0.0f}};
    CHECK_NOTHROW(ngi::Model::load(ngi::test::device(), write_file("set_ok", set_ok, set_cfg)));
    bad = set_ok;
    bad[2].shape = {5, 3};
    expect_error(write_file("set_shape", bad, set_cfg), "tensor 'rho.0.weight' is [5, 3], expected [5, 9]");
    ngi::ModelOptions opt;
    opt.mlp_path = "fused";
    REQUIRE_THROWS_WITH(ngi::Model::load(ngi::test::device(), write_file("ok", ok, cfg), opt),
                        Contains("mlp_path applies to the mlp family"));
}

// ---- the ops the runner added ------------------------------------------------------------------------------

namespace {

// Planar max and mean over items [begin, end) of every channel, in double.
void check_pool_planar(int channels, int ld, int begin, int end, int max_items_per_launch, std::mt19937& rng) {
    using namespace ngi::detail;
    Context& ctx = ngi::test::ctx();
    const std::vector<float> x = ngi::test::random_vector(std::size_t(channels) * ld, rng, -3.0f, 2.0f);
    const std::size_t off = 5;  // pooled from a nonzero offset
    std::vector<float> padded(off, 0.0f);
    padded.insert(padded.end(), x.begin(), x.end());
    Buffer xb = ngi::test::upload(padded);
    Buffer pb = ctx.alloc((off + 2 * std::size_t(channels)) * sizeof(float), "pooled");
    SetPool pool(ctx);
    pool.pool_planar(ctx, xb.get(), off, channels, ld, begin, end, PoolMode::Max, pb.get(), off, max_items_per_launch);
    pool.pool_planar(ctx, xb.get(), off, channels, ld, begin, end, PoolMode::Mean, pb.get(), off + channels,
                     max_items_per_launch);
    const std::vector<float> got = ngi::test::download(pb, 2 * std::size_t(channels), off);
    for (int c = 0; c < channels; ++c) {
        double mx = -INFINITY, sum = 0;
        for (int i = begin; i < end; ++i) {
            mx = std::max(mx, double(x[std::size_t(c) * ld + i]));
            sum += x[std::size_t(c) * ld + i];
        }
        const int n = end - begin;
        CAPTURE(channels, ld, begin, end, max_items_per_launch, c);
        CHECK(got[c] == float(n > 0 ? mx : 0.0));
        CHECK(got[channels + c] == Approx(n > 0 ? sum / n : 0.0).margin(1e-5));
    }
}

}  // namespace

TEST_CASE("planar set pooling (one set, chunked launches) matches a double reference", "[voxel_sh][pool]") {
    std::mt19937 rng(7);
    for (int n : {1, 2, 63, 64, 65, 1001, 10007}) check_pool_planar(3, n, 0, n, 0, rng);
    check_pool_planar(5, 300, 17, 251, 0, rng);   // a range inside the rows
    check_pool_planar(4, 100, 40, 40, 0, rng);    // empty: 0
    check_pool_planar(7, 5000, 0, 5000, 640, rng);  // 8 chunks (the split llvmpipe's loop limit forces)
    check_pool_planar(2, 1001, 3, 1000, 1, rng);    // one item per launch
}

TEST_CASE("per-channel affine into planar (points and planar in) and the residual add match a reference",
          "[voxel_sh][elementwise]") {
    using namespace ngi::detail;
    Context& ctx = ngi::test::ctx();
    Elementwise ew(ctx);
    std::mt19937 rng(11);
    for (int n : {1, 37, 1001}) {
        const int channels = 10;
        std::vector<float> x = ngi::test::random_vector(std::size_t(channels) * n, rng, -100.0f, 100.0f);
        x[0] = NAN;
        x[x.size() - 1] = FLT_MAX;
        const std::vector<float> scale = ngi::test::random_vector(channels, rng, -3.0f, 3.0f);
        const std::vector<float> shift = ngi::test::random_vector(channels, rng, -1.0f, 1.0f);
        Buffer xb = ngi::test::upload(x), sb = ngi::test::upload(scale), tb = ngi::test::upload(shift);
        Buffer yb = ctx.alloc((3 + std::size_t(channels) * n) * sizeof(float), "affine out");
        for (bool points : {true, false}) {
            CAPTURE(n, points);
            // points: x is [n][C]; planar: x is [C][n].
            ew.channel_affine(ctx, xb.get(), 0, points ? channels : 1, points ? 1 : n, channels, n, sb.get(), tb.get(),
                              yb.get(), 3);
            const std::vector<float> y = ngi::test::download(yb, std::size_t(channels) * n, 3);
            for (int c = 0; c < channels; ++c)
                for (int i = 0; i < n; ++i) {
                    const float v = x[points ? std::size_t(i) * channels + c : std::size_t(c) * n + i];
                    const float got = y[std::size_t(c) * n + i];
                    const double want = double(scale[c]) * v + shift[c];
                    if (std::isnan(v)) CHECK(std::isnan(got));
                    else if (!std::isfinite(want) || std::abs(want) > 1e38) CHECK(std::abs(got) > 1e38f);
                    else CHECK(got == Approx(want).epsilon(1e-6).margin(1e-6));
                }
        }
        // add: a[off..] += b[off..]
        const std::vector<float> a = ngi::test::random_vector(std::size_t(n) + 2, rng), b = ngi::test::random_vector(std::size_t(n) + 4, rng);
        Buffer ab = ngi::test::upload(a), bb = ngi::test::upload(b);
        ew.add(ctx, View{ab.get(), 2, ngi::Shape{1, 1, n}}, View{bb.get(), 4, ngi::Shape{n, 1, 1}});
        const std::vector<float> sum = ngi::test::download(ab, std::size_t(n) + 2);
        CHECK(sum[0] == a[0]);
        CHECK(sum[1] == a[1]);
        for (int i = 0; i < n; ++i) CHECK(sum[2 + i] == a[2 + i] + b[4 + i]);
    }
}

TEST_CASE("voxel_sh kernels at small shapes (oclgrind: bounds, races, uninitialized reads)",
          "[voxel_sh][oclgrind]") {
    using namespace ngi::detail;
    Context& ctx = ngi::test::ctx();
    std::mt19937 rng(3);
    check_pool_planar(2, 70, 1, 69, 32, rng);
    Elementwise ew(ctx);
    const std::vector<float> x = ngi::test::random_vector(3 * 5, rng), s = {1.0f, 2.0f, 0.0f}, t = {0.0f, -1.0f, 3.0f};
    Buffer xb = ngi::test::upload(x), sb = ngi::test::upload(s), tb = ngi::test::upload(t);
    Buffer yb = ctx.alloc(15 * sizeof(float), "affine out");
    ew.channel_affine(ctx, xb.get(), 0, 3, 1, 3, 5, sb.get(), tb.get(), yb.get(), 0);
    const std::vector<float> y = ngi::test::download(yb, 15);
    for (int c = 0; c < 3; ++c)
        for (int i = 0; i < 5; ++i) CHECK(y[std::size_t(c) * 5 + i] == Approx(s[c] * x[std::size_t(i) * 3 + c] + t[c]));
    ew.add(ctx, View{yb.get(), 0, ngi::Shape{15, 1, 1}}, View{xb.get(), 0, ngi::Shape{15, 1, 1}});
    const std::vector<float> z = ngi::test::download(yb, 15);
    for (int k = 0; k < 15; ++k) CHECK(z[k] == y[k] + x[k]);

    // A whole tiny set network (affine, guard, GEMM layers, pooling, the per-scene bias of N = 1): what the
    // runner's buffers hold between the kernels.
    nlohmann::json cfg = tiny_config();
    cfg.erase("width");
    cfg.erase("blocks");
    cfg["architecture"] = "set";
    cfg["phi"] = {3};
    cfg["rho"] = {5};
    const std::vector<Entry> set = {{"phi.0.weight", {3, 10}, 0.1f}, {"phi.0.bias", {3}, 0.0f},
                                    {"rho.0.weight", {5, 9}, 0.1f},  {"rho.0.bias", {5}, 0.0f},
                                    {"rho.1.weight", {27, 5}, 0.1f}, {"rho.1.bias", {27}, 0.0f}};
    ngi::Model m = ngi::Model::load(ngi::test::device(), write_file("oclgrind_set", set, cfg));
    ngi::Tensor in({3, 10});
    in.data = ngi::test::random_vector(30, rng);
    CHECK(ngi::test::all_finite(m.run(in).data));
}
