// Model files that must be refused with a clear message naming the problem (and the file or tensor).
#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "models/family.hpp"
#include "models/safetensors.hpp"
#include "ngi.h"
#include "ngi/error.hpp"
#include "ngi/model.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;

namespace {

struct Entry {
    std::string name;
    std::vector<int> shape;
    float value;
};

// Writes a safetensors file from (name, shape, constant value) entries plus a config; `mutate` may edit the
// header JSON or the final bytes to produce the broken variants.
std::string write_file(const std::string& stem, const std::vector<Entry>& entries, const nlohmann::json& config,
                       const std::function<void(nlohmann::json&)>& edit_header = {},
                       const std::function<void(std::string&)>& edit_bytes = {}) {
    nlohmann::json header;
    std::string data;
    for (const auto& e : entries) {
        std::size_t n = 1;
        for (int d : e.shape) n *= d;
        std::vector<float> v(n, e.value);
        header[e.name] = {{"dtype", "F32"}, {"shape", e.shape}, {"data_offsets", {data.size(), data.size() + 4 * n}}};
        data.append(reinterpret_cast<const char*>(v.data()), 4 * n);
    }
    header["__metadata__"] = {{"ngi", config.dump()}};
    if (edit_header) edit_header(header);
    std::string h = header.dump();
    while (h.size() % 8) h += ' ';
    std::string bytes(8, '\0');
    std::uint64_t len = h.size();
    for (int i = 0; i < 8; ++i) bytes[i] = char((len >> (8 * i)) & 0xff);
    bytes += h + data;
    if (edit_bytes) edit_bytes(bytes);
    const fs::path p = fs::temp_directory_path() / ("ngi_test_" + stem + ".safetensors");
    std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    return p.string();
}

// The smallest valid pix2pix generator: num_downs 5, ngf 1, 1 -> 1 channels.
nlohmann::json tiny_config() {
    return {{"family", "pix2pix_unet"}, {"input_nc", 1}, {"output_nc", 1}, {"ngf", 1}, {"num_downs", 5},
            {"bn_mode", "running"}};
}

std::vector<Entry> tiny_entries() {
    std::vector<Entry> e;
    auto bn = [&](const std::string& p, int c) {
        e.push_back({p + ".weight", {c}, 1.0f});
        e.push_back({p + ".bias", {c}, 0.0f});
        e.push_back({p + ".running_mean", {c}, 0.0f});
        e.push_back({p + ".running_var", {c}, 1.0f});
    };
    // level 0
    e.push_back({"model.model.0.weight", {1, 1, 4, 4}, 0.1f});
    e.push_back({"model.model.3.weight", {2, 1, 4, 4}, 0.1f});
    e.push_back({"model.model.3.bias", {1}, 0.0f});
    // levels 1..3 (middle) and 4 (innermost); channels 1 -> 2 -> 4 -> 8 -> 8
    const int inner[5] = {1, 2, 4, 8, 8};
    std::string seq = "model.model.1.model";
    for (int i = 1; i <= 3; ++i) {
        e.push_back({seq + ".1.weight", {inner[i], inner[i - 1], 4, 4}, 0.1f});
        bn(seq + ".2", inner[i]);
        e.push_back({seq + ".5.weight", {2 * inner[i], inner[i - 1], 4, 4}, 0.1f});
        bn(seq + ".6", inner[i - 1]);
        seq += ".3.model";
    }
    e.push_back({seq + ".1.weight", {8, 8, 4, 4}, 0.1f});
    e.push_back({seq + ".3.weight", {8, 8, 4, 4}, 0.1f});
    bn(seq + ".4", 8);
    return e;
}

void expect_error(const std::string& path, const std::string& fragment) {
    INFO("file " << path);
    REQUIRE_THROWS_WITH(ngi::Model::load(ngi::test::device(), path), Contains(fragment));
}

// A safetensors file's bytes: the 8-byte header length, the header as given, then the data.
std::string safetensors_bytes(const std::string& header_json, const std::string& data) {
    std::string b(8, '\0');
    for (int i = 0; i < 8; ++i) b[i] = char((std::uint64_t(header_json.size()) >> (8 * i)) & 0xff);
    return b + header_json + data;
}

// The InputError message of parsing `config` as the model config of m.safetensors ("" if it parsed).
std::string model_config_error(const nlohmann::json& config) {
    try {
        ngi::detail::parse_model_config(config.dump(), "m.safetensors");
    } catch (const ngi::InputError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST_CASE("a valid tiny model loads and runs and its output is finite", "[model][file][oclgrind]") {
    auto m = ngi::Model::load(ngi::test::device(), write_file("valid", tiny_entries(), tiny_config()));
    ngi::Tensor x({1, 1, 32, 64});
    for (std::size_t i = 0; i < x.size(); ++i) x.data[i] = float(i % 7) - 3.0f;
    const ngi::Tensor y = m.run(x);
    CHECK(y.shape == std::vector<int>{1, 1, 32, 64});
    CHECK(ngi::test::all_finite(y.data));
    REQUIRE_THROWS_WITH(m.run(ngi::Tensor({1, 1, 30, 64})), Contains("multiple of 2^num_downs"));
    REQUIRE_THROWS_WITH(m.run(ngi::Tensor({1, 2, 32, 64})), Contains("expected [1, 1, H, W]"));
}

TEST_CASE("broken model files give clear errors", "[model][file][oclgrind]") {
    const auto cfg = tiny_config();
    auto entries = tiny_entries();

    SECTION("missing tensor") {
        auto e = entries;
        e.erase(e.begin());
        expect_error(write_file("missing", e, cfg), "missing tensors: model.model.0.weight");
    }
    SECTION("unexpected tensor") {
        auto e = entries;
        e.push_back({"model.extra.weight", {3}, 0.0f});
        expect_error(write_file("unexpected", e, cfg), "unexpected tensors: model.extra.weight");
    }
    SECTION("shape mismatch") {
        auto e = entries;
        e[0].shape = {1, 2, 4, 4};
        expect_error(write_file("shape", e, cfg), "model.model.0.weight is [1, 2, 4, 4], expected [1, 1, 4, 4]");
    }
    SECTION("non-finite weight") {
        auto e = entries;
        e[1].value = std::numeric_limits<float>::quiet_NaN();
        expect_error(write_file("nan", e, cfg), "tensor 'model.model.3.weight': value 0 is not finite");
    }
    SECTION("truncated data") {
        expect_error(write_file("truncated", entries, cfg, {}, [](std::string& b) { b.resize(b.size() - 10); }),
                     "the file is truncated");
    }
    SECTION("header length beyond the file") {
        expect_error(write_file("header_len", entries, cfg, {}, [](std::string& b) { b[5] = 0x7f; }),
                     "runs beyond the end of the file");
    }
    SECTION("malformed JSON header") {
        expect_error(write_file("json", entries, cfg, {}, [](std::string& b) { b[8] = '['; b[9] = '{'; }),
                     "malformed JSON header");
    }
    SECTION("no architecture metadata") {
        expect_error(write_file("nometa", entries, cfg, [](nlohmann::json& h) { h.erase("__metadata__"); }),
                     "no __metadata__[\"ngi\"]");
    }
    SECTION("bad input/output ranges") {
        for (const auto& [key, value] : std::vector<std::pair<std::string, nlohmann::json>>{
                 {"input_range", {1, -1}}, {"input_range", {0, 0}}, {"output_range", {0, 1e300}},
                 {"input_range", {-1}}, {"output_range", "wide"}}) {
            auto c = cfg;
            c[key] = value;
            expect_error(write_file("range", entries, c), key);
        }
    }
    SECTION("unknown family") {
        auto c = cfg;
        c["family"] = "resnet";
        expect_error(write_file("family", entries, c), "family 'resnet' is not supported");
    }
    SECTION("file too short") {
        expect_error(write_file("short", entries, cfg, {}, [](std::string& b) { b.resize(5); }), "too short");
    }
    SECTION("missing file") { expect_error("/nonexistent/model.safetensors", "cannot open file"); }
}

TEST_CASE("a bn_eps that is 0 in float32, or a negative running variance, is refused at load", "[model][file]") {
    // Issue 31: bn_eps 1e-300 passed "(0, 1]" as a double and became 0 in float32; per-image batch norm of an
    // all-zero input then divided 0 by sqrt(0 + 0): every output NaN, exit 0, no warning.
    auto cfg = tiny_config();
    cfg["bn_mode"] = "per_image";
    auto m = ngi::Model::load(ngi::test::device(), write_file("eps_ok", tiny_entries(), cfg));
    const ngi::Tensor zeros({1, 1, 32, 32});
    CHECK(ngi::test::all_finite(m.run(zeros).data));
    for (double eps : {1e-300, 1e-40}) {
        cfg["bn_eps"] = eps;
        INFO("bn_eps " << eps);
        expect_error(write_file("eps_tiny", tiny_entries(), cfg), "field 'bn_eps' must be a number in (0, 1]");
        expect_error(write_file("eps_tiny", tiny_entries(), cfg), "representable in float32");
    }
    // Running statistics: a negative variance made the folded scale sqrt(< 0) = NaN.
    auto e = tiny_entries();
    for (auto& t : e)
        if (t.name.ends_with(".running_var")) t.value = -1.0f;
    expect_error(write_file("var_negative", e, tiny_config()), ".running_var' channel 0 is -1");
}

TEST_CASE("every float field of a model config must survive float32", "[model][limits]") {
    const nlohmann::json unet = {{"family", "pix2pix_unet"}, {"input_nc", 12}, {"output_nc", 3}, {"ngf", 8},
                                 {"num_downs", 6}, {"bn_eps", 1e-5}, {"leaky_slope", 0.2}, {"dropout_p", 0.5},
                                 {"input_range", {-1, 1}}, {"output_range", {-1, 1}}};
    REQUIRE(model_config_error(unet).empty());
    // bn_eps 1e-300 passed "(0, 1]" as a double and was 0 in float32: an all-zero input gave 49,152 NaN outputs.
    for (const auto& [key, value] : std::vector<std::pair<std::string, nlohmann::json>>{
             {"bn_eps", 1e-300}, {"bn_eps", 1e-40}, {"leaky_slope", 1e-300}, {"dropout_p", 1e-45},
             {"input_range", {1e-300, 2e-300}}, {"output_range", {-1e-39, 1e-39}}}) {
        nlohmann::json c = unet;
        c[key] = value;
        INFO(key << " = " << value.dump());
        CHECK_THAT(model_config_error(c),
                   Contains("m.safetensors") && Contains("'" + key + "'") && Contains("representable in float32"));
    }
    nlohmann::json ok = unet;
    ok["bn_eps"] = 1.2e-38;  // a normal float: kept
    ok["leaky_slope"] = 0.0;  // zero is exact
    CHECK(model_config_error(ok).empty());

    // The other families: an MLP layer's slope, neural_gi's scene box, voxel_sh's statistics.
    const nlohmann::json mlp = {{"family", "mlp"}, {"input_nc", 3},
                                {"layers", {{{"out", 1}, {"activation", "leaky_relu"}, {"slope", 0.1}}}}};
    REQUIRE(model_config_error(mlp).empty());
    nlohmann::json bad = mlp;
    bad["layers"][0]["slope"] = 1e-300;
    CHECK_THAT(model_config_error(bad), Contains("layers[0].slope") && Contains("float32"));

    const nlohmann::json neural = {
        {"family", "neural_gi"}, {"input_nc", 18}, {"output_nc", 3}, {"ngf", 8}, {"num_downs", 5},
        {"dropout", "off"},
        {"neural_gi", {{"buffer_channels", 4}, {"mlp_width", 8}, {"mlp_depth", 2}, {"skip_layer", 1}, {"decode", "exp"},
                       {"scene_box", {{"min", {0, 0, 0}}, {"max", {8, 8, 8}}}}}}};
    REQUIRE(model_config_error(neural).empty());
    bad = neural;
    bad["neural_gi"]["scene_box"]["min"] = {1e-300, 0, 0};
    CHECK_THAT(model_config_error(bad), Contains("neural_gi.scene_box") && Contains("float32"));

    nlohmann::json voxel = {{"family", "voxel_sh"}, {"architecture", "mlp"}, {"grid", {4, 4, 4}}, {"hidden", {8}},
                            {"input_lo", std::vector<double>(10, 0.0)}, {"input_hi", std::vector<double>(10, 1.0)},
                            {"output_mean", std::vector<double>(27, 0.0)}, {"output_std", std::vector<double>(27, 1.0)}};
    REQUIRE(model_config_error(voxel).empty());
    voxel["output_std"][3] = 1e-300;  // would be 0 in float32: every output the mean
    CHECK_THAT(model_config_error(voxel), Contains("output_std") && Contains("float32"));
}

TEST_CASE("safetensors with trailing bytes or a NUL-padded header are refused", "[model][limits]") {
    const std::string header = R"({"w": {"dtype": "F32", "shape": [2], "data_offsets": [0, 8]}})";
    const std::string data(8, '\0');
    REQUIRE(ngi::detail::parse_safetensors(safetensors_bytes(header, data), "ok").tensors.size() == 1);
    // Space padding is the format's own: accepted.
    REQUIRE(ngi::detail::parse_safetensors(safetensors_bytes(header + "    ", data), "ok").tensors.size() == 1);
    CHECK_THROWS_WITH(ngi::detail::parse_safetensors(safetensors_bytes(header, data + "junk"), "tail.safetensors"),
                      Contains("tail.safetensors") && Contains("4 trailing bytes after the last tensor"));
    CHECK_THROWS_WITH(
        ngi::detail::parse_safetensors(safetensors_bytes(header + std::string(6, '\0'), data), "nul.safetensors"),
        Contains("nul.safetensors") && Contains("NUL byte"));
    // A header of only metadata holds no data: any byte after it is trailing.
    CHECK_THROWS_WITH(ngi::detail::parse_safetensors(safetensors_bytes(R"({"__metadata__": {}})", "x"), "meta"),
                      Contains("1 trailing bytes"));
}

TEST_CASE("output_mode: lightmap by default, indirect for pix2pix_unet, anything else refused", "[model][file]") {
    const auto entries = tiny_entries();
    auto cfg = tiny_config();
    // Absent: the thesis's mode.
    CHECK(ngi::Model::load(ngi::test::device(), write_file("mode_default", entries, cfg)).config().output_mode ==
          "lightmap");
    cfg["output_mode"] = "indirect";
    cfg["required"] = {"output_mode"};  // what ngi.model_file writes for it: older readers refuse the file
    CHECK(ngi::Model::load(ngi::test::device(), write_file("mode_indirect", entries, cfg)).config().output_mode ==
          "indirect");
    cfg["output_mode"] = "lightmap";
    CHECK(ngi::Model::load(ngi::test::device(), write_file("mode_lightmap", entries, cfg)).config().output_mode ==
          "lightmap");

    // An unknown value names the file, the value and the allowed values.
    cfg["output_mode"] = "residual";
    const std::string bad = write_file("mode_bad", entries, cfg);
    REQUIRE_THROWS_WITH(ngi::Model::load(ngi::test::device(), bad),
                        Contains(bad) && Contains("output_mode") && Contains("\"residual\"") &&
                            Contains("\"lightmap\"") && Contains("\"indirect\""));
    cfg["output_mode"] = 1;
    expect_error(write_file("mode_type", entries, cfg), "field 'output_mode' must be a string");

    // Only pix2pix_unet generators compose with the frame's direct light.
    auto di = tiny_config();
    di["family"] = "deepillumination";
    di["num_downs"] = 8;
    di["output_mode"] = "indirect";
    expect_error(write_file("mode_di", entries, di), "only family pix2pix_unet supports; this is family deepillumination");
    const nlohmann::json vox = {{"family", "voxel_sh"}, {"output_mode", "indirect"}};
    expect_error(write_file("mode_vox", {}, vox), "only family pix2pix_unet has an output mode");
}

TEST_CASE("NaN, Inf and far out-of-range inputs are sanitized and counted", "[model][extremes][oclgrind]") {
    auto m = ngi::Model::load(ngi::test::device(), write_file("sanitize", tiny_entries(), tiny_config()));
    ngi::Tensor x({1, 1, 32, 32});  // zeros; input_range is the default [-1, 1]
    x.data[3] = std::numeric_limits<float>::quiet_NaN();
    x.data[40] = std::numeric_limits<float>::infinity();
    x.data[41] = -std::numeric_limits<float>::infinity();
    x.data[42] = 1e30f;    // far above the range: clamped like +Inf
    x.data[43] = -1.5f;    // beyond the 1/1024 margin: clamped
    x.data[44] = 1.0009f;  // within the margin (rounding at the range's end): unchanged, not counted
    x.data[45] = -1.0009f;
    ngi::RunInfo info;
    const ngi::Tensor y = m.run(x, &info);
    CHECK(info.sanitized_inputs == 5);
    CHECK(ngi::test::all_finite(y.data));

    // The clamped values equal the range's ends exactly: same output as an input holding 1 / -1 there.
    ngi::Tensor clean = x;
    clean.data[3] = 0.0f;
    clean.data[40] = clean.data[42] = 1.0f;
    clean.data[41] = clean.data[43] = -1.0f;
    ngi::RunInfo clean_info;
    const ngi::Tensor yc = m.run(clean, &clean_info);
    CHECK(clean_info.sanitized_inputs == 0);
    CHECK(yc.data == y.data);
}

// Finite values near FLT_MAX overflow the first convolution's sums to Inf, and per-image batch norm turns that into
// NaN (Inf - Inf): before they were clamped, an all-3.4e38 input gave an all-NaN output and no count.
TEST_CASE("an input of finite values near FLT_MAX gives a finite output and a full count", "[model][extremes][oclgrind]") {
    auto m = ngi::Model::load(ngi::test::device(), write_file("flt_max", tiny_entries(), tiny_config()),
                              ngi::ModelOptions{"per_image", "", ""});
    for (const float v : {3.4e38f, -3.4e38f, std::numeric_limits<float>::max()}) {
        ngi::Tensor x({1, 1, 32, 64});
        std::fill(x.data.begin(), x.data.end(), v);
        ngi::RunInfo info;
        const ngi::Tensor y = m.run(x, &info);
        CHECK(info.sanitized_inputs == int(x.size()));
        CHECK(ngi::test::all_finite(y.data));
        std::fill(x.data.begin(), x.data.end(), v > 0 ? 1.0f : -1.0f);  // what the clamp makes of it
        CHECK(m.run(x).data == y.data);
    }
}

TEST_CASE("broken mlp model files give clear errors naming the field or tensor", "[model][file][mlp]") {
    const nlohmann::json cfg = {{"family", "mlp"}, {"input_nc", 3},
                                {"layers", {{{"out", 4}, {"activation", "tanh"}}, {{"out", 2}}}}};
    const std::vector<Entry> ok = {{"layers.0.weight", {4, 3}, 0.1f}, {"layers.0.bias", {4}, 0.0f},
                                   {"layers.1.weight", {2, 4}, 0.2f}, {"layers.1.bias", {2}, 0.0f}};
    {
        ngi::Model m = ngi::Model::load(ngi::test::device(), write_file("mlp_ok", ok, cfg));
        CHECK(m.config().output_nc == 2);
        ngi::Tensor x({5, 3});
        x.data = {1, 2, 3, 0, 0, 0, -1, -2, -3, NAN, INFINITY, 0.5f, 1, 1, 1};
        ngi::RunInfo info;
        const ngi::Tensor y = m.run(x, &info);
        REQUIRE(y.shape == std::vector<int>{5, 2});
        CHECK(info.sanitized_inputs == 2);  // NaN and +Inf, like the generator's guard
        CHECK(ngi::test::all_finite(y.data));
        // 4 x tanh(0.1 * (1 + 2 + 3)) * 0.2 for item 0
        CHECK(y.data[0] == Approx(4 * std::tanh(0.6) * 0.2).epsilon(1e-5));
        REQUIRE_THROWS_WITH(m.run(ngi::Tensor({5, 4})), Contains("[N, 3]"));
    }
    auto with = [&](const char* key, nlohmann::json value) {
        nlohmann::json c = cfg;
        c[key] = value;
        return c;
    };
    expect_error(write_file("mlp_act", ok, with("layers", {{{"out", 4}, {"activation", "swish"}}, {{"out", 2}}})),
                 "'layers[0].activation' must be one of");
    expect_error(write_file("mlp_nolayers", ok, with("layers", nlohmann::json::array())), "'layers' must be");
    expect_error(write_file("mlp_enc", ok, with("encoding", {{"order", "zigzag"}})), "'encoding.order'");
    expect_error(write_file("mlp_outnc", ok, with("output_nc", 3)), "'output_nc' must be the last layer's width (2)");
    std::vector<Entry> bad = ok;
    bad[2].shape = {2, 5};
    expect_error(write_file("mlp_shape", bad, cfg), "tensor 'layers.1.weight' is [2, 5], expected [2, 4]");
    bad = ok;
    bad.pop_back();
    bad.push_back({"layers.7.weight", {1}, 0.0f});
    expect_error(write_file("mlp_extra", bad, cfg), "tensor 'layers.7.weight' is not part of this mlp");
    bad = ok;
    bad.erase(bad.begin());
    expect_error(write_file("mlp_missing", bad, cfg), "tensor 'layers.0.weight' is missing");
    bad = ok;
    bad[1].value = NAN;
    expect_error(write_file("mlp_nan", bad, cfg), "tensor 'layers.0.bias': value 0 is not finite");
    REQUIRE_THROWS_WITH(ngi::Model::load(ngi::test::device(), write_file("mlp_path", ok, cfg),
                                         ngi::ModelOptions{"", "", "turbo"}),
                        Contains("'turbo'"));
}

TEST_CASE("every registered family's parser sets the traits the code outside models/ chooses by", "[model][file]") {
    using ngi::ModelInput;
    struct Case {
        nlohmann::json config;
        ModelInput input;
        bool has_network, output_keeps_size;
    };
    // A graph with no tensors whose output is C x 1 x 1 (it resamples), and an "nc" one (items).
    const nlohmann::json pool = nlohmann::json::parse(R"({"family": "graph", "input_nc": 2, "graph": {"input": "x",
        "output": "y", "nodes": [{"name": "pool", "op": "global_avg_pool", "inputs": ["x"], "output": "y"}]}})");
    const nlohmann::json relu = nlohmann::json::parse(R"({"family": "graph", "input_nc": 2, "graph": {"layout": "nc",
        "input": "x", "output": "y", "nodes": [{"name": "relu", "op": "activation", "inputs": ["x"], "output": "y",
        "activation": "relu"}]}})");
    const nlohmann::json voxel = {{"family", "voxel_sh"}, {"architecture", "mlp"}, {"grid", {4, 4, 4}}, {"hidden", {8}},
                                  {"input_lo", std::vector<double>(10, 0.0)}, {"input_hi", std::vector<double>(10, 1.0)},
                                  {"output_mean", std::vector<double>(27, 0.0)},
                                  {"output_std", std::vector<double>(27, 1.0)}};
    const nlohmann::json neural = nlohmann::json::parse(R"({"family": "neural_gi", "input_nc": 18, "output_nc": 3,
        "ngf": 8, "num_downs": 5, "dropout": "off", "neural_gi": {"buffer_channels": 4, "mlp_width": 8, "mlp_depth": 2,
        "skip_layer": 1, "decode": "exp"}})");
    // A config of every family, keyed by its name: a family added to the registry fails here until its config and
    // traits are added (graph: both layouts).
    const std::map<std::string, std::vector<Case>> cases = {
        {"pix2pix_unet", {{tiny_config(), ModelInput::image, true, true}}},
        {"deepillumination",
         {{nlohmann::json::parse(R"({"family": "deepillumination", "input_nc": 1, "output_nc": 1, "ngf": 1,
               "num_downs": 8})"),
           ModelInput::image, true, true}}},
        {"mlp",
         {{nlohmann::json::parse(R"({"family": "mlp", "input_nc": 3, "layers": [{"out": 1}]})"), ModelInput::items,
           true, true}}},
        {"voxel_sh", {{voxel, ModelInput::items, true, true}}},
        {"neural_gi", {{neural, ModelInput::image, true, true}}},
        {"graph", {{pool, ModelInput::image, true, false}, {relu, ModelInput::items, true, false}}},
        {"ssgi", {{nlohmann::json::parse(R"({"family": "ssgi"})"), ModelInput::image, false, true}}},
        {"pixel_cnn",
         {{nlohmann::json::parse(R"({"family": "pixel_cnn", "input_nc": 2, "layers": [{"out": 3, "kernel": 3}]})"),
           ModelInput::image, true, true}}},
    };
    std::size_t families = 0;
    for (const ngi::detail::ModelFamily* f : ngi::detail::model_families()) {
        ++families;
        const std::string name(f->name);
        INFO("family " << name);
        const auto it = cases.find(name);
        REQUIRE(it != cases.end());
        for (const Case& k : it->second) {
            INFO("config " << k.config.dump());
            const ngi::detail::FamilyConfig parsed = ngi::detail::parse_family_config(k.config.dump(), "m.safetensors");
            REQUIRE(parsed.family == f);
            CHECK(parsed.config.family == name);
            CHECK(parsed.config.input == k.input);
            CHECK(parsed.config.has_network == k.has_network);
            CHECK(parsed.config.output_keeps_size == k.output_keeps_size);
        }
    }
    CHECK(families == cases.size());  // no config left of a family the registry no longer lists

    // The tensorless ones load: an ssgi rung, and the pooling graph, whose output the network sizes.
    ngi::Device& dev = ngi::test::device();
    const ngi::Model rung = ngi::Model::load(dev, write_file("traits_ssgi", {}, {{"family", "ssgi"}}));
    CHECK(!rung.config().has_network);
    ngi::Model graph = ngi::Model::load(dev, write_file("traits_pool", {}, pool));
    CHECK(!graph.config().output_keeps_size);
    CHECK(graph.run(ngi::Tensor({1, 2, 4, 4})).shape == std::vector<int>{1, 2, 1, 1});
}

TEST_CASE("a family parser that leaves a trait unset fails every parse of its family", "[model][file]") {
    ngi::detail::FamilyConfig parsed;
    parsed.traits.input = ngi::ModelInput::items;  // output_keeps_size forgotten
    parsed.traits.has_network = true;
    bool input_error = false;
    std::string message;
    try {
        ngi::detail::apply_family_traits(parsed, "new_family");
    } catch (const ngi::InputError&) {
        input_error = true;
    } catch (const ngi::Error& e) {
        message = e.what();
    }
    CHECK(!input_error);  // a bug of the library, not a file's fault
    CHECK_THAT(message, Contains("new_family") && Contains("'output_keeps_size'"));
    parsed.traits.output_keeps_size = false;
    ngi::detail::apply_family_traits(parsed, "new_family");
    CHECK(parsed.config.input == ngi::ModelInput::items);
    CHECK(parsed.config.has_network);
    CHECK(!parsed.config.output_keeps_size);
}

TEST_CASE("ngi_model_run refuses a network whose output has another size than its input", "[model][file]") {
    // A graph's global average pool makes C x 1 x 1: the C call's output_nc x height x width would be read past it.
    const std::string path = write_file("c_pool", {}, nlohmann::json::parse(R"({"family": "graph", "input_nc": 2,
        "graph": {"input": "x", "output": "y", "nodes": [{"name": "pool", "op": "global_avg_pool", "inputs": ["x"],
        "output": "y"}]}})"));
    const char* spec = std::getenv("NGI_TEST_DEVICE");
    ngi_device* cdev = nullptr;
    ngi_model* cm = nullptr;
    REQUIRE(ngi_device_open(spec ? spec : "cpu", &cdev) == NGI_OK);
    REQUIRE(ngi_model_load(cdev, path.c_str(), &cm) == NGI_OK);
    ngi_model_input input = NGI_INPUT_ITEMS;
    int has_network = -1, keeps = -1;
    CHECK(ngi_model_traits(cm, &input, &has_network, &keeps) == NGI_OK);
    CHECK((input == NGI_INPUT_IMAGE && has_network == 1 && keeps == 0));
    std::vector<float> x(2 * 4 * 4, 0.5f), y(2 * 4 * 4, -1.0f);
    CHECK(ngi_model_run(cm, x.data(), x.size() * sizeof(float), 4, 4, y.data(), y.size() * sizeof(float)) ==
          NGI_ERROR_INPUT);
    CHECK_THAT(std::string(ngi_last_error()), Contains("[1, 2, 1, 1]") && Contains("resamples"));
    CHECK(ngi_model_release(cm) == NGI_OK);
    CHECK(ngi_device_release(cdev) == NGI_OK);
}
