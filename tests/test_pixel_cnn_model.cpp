// Family "pixel_cnn" (models/pixel_cnn_family.cpp, docs/MODEL_FORMAT.md "pixel_cnn"): model files with random
// weights over random odd shapes against a naive C++ reference (tests/reference.hpp: zero-padded k x k convolutions,
// bias, activation, in double), on Model::run and Model::enqueue; PyTorch parity (tests/parity/
// make_pixel_cnn_parity.py: torch.nn.Conv2d stacks in float64); and the refusals of broken configs and files.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "models/family.hpp"
#include "ngi/device_buffer.hpp"
#include "ngi/error.hpp"
#include "ngi/model.hpp"
#include "reference.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;

namespace {

struct CnnTensor {
    std::string name;
    std::vector<int> shape;
    std::vector<float> data;
};

// A safetensors file of `tensors` (F32) and `config` as __metadata__["ngi"], in the test's temporary folder.
std::string write_pixel_cnn_file(const std::string& stem, const std::vector<CnnTensor>& tensors,
                                 const nlohmann::json& config) {
    nlohmann::json header;
    std::string data;
    for (const auto& t : tensors) {
        header[t.name] = {{"dtype", "F32"}, {"shape", t.shape},
                          {"data_offsets", {data.size(), data.size() + 4 * t.data.size()}}};
        data.append(reinterpret_cast<const char*>(t.data.data()), 4 * t.data.size());
    }
    header["__metadata__"] = {{"ngi", config.dump()}};
    std::string h = header.dump();
    h.append((8 - h.size() % 8) % 8, ' ');
    const fs::path path = fs::temp_directory_path() / ("ngi_test_pixel_cnn_" + stem + ".safetensors");
    std::ofstream out(path, std::ios::binary);
    const std::uint64_t n = h.size();
    out.write(reinterpret_cast<const char*>(&n), 8);
    out << h << data;
    return path.string();
}

struct CnnLayer {
    int out, kernel;
    std::string activation;
    float slope;
    bool bias;
};

// ngi::ref::activate's codes.
int activation_code(const std::string& a) {
    return a == "relu" ? 1 : a == "leaky_relu" ? 2 : a == "tanh" ? 3 : a == "sigmoid" ? 4 : 0;
}

struct CnnCase {
    nlohmann::json config;
    std::vector<CnnTensor> tensors;
    std::vector<CnnLayer> layers;
    int input_nc;
};

CnnCase random_case(std::mt19937& rng, int input_nc, const std::vector<CnnLayer>& layers) {
    CnnCase c{{{"format_version", 1}, {"family", "pixel_cnn"}, {"input_nc", input_nc}, {"layers", nlohmann::json::array()}},
              {}, layers, input_nc};
    int in = input_nc;
    for (std::size_t i = 0; i < layers.size(); ++i) {
        const CnnLayer& l = layers[i];
        nlohmann::json j = {{"out", l.out}, {"kernel", l.kernel}, {"activation", l.activation}};
        if (l.activation == "leaky_relu") j["slope"] = l.slope;
        c.config["layers"].push_back(j);
        const float bound = 1.0f / std::sqrt(float(in * l.kernel * l.kernel));  // nn.Conv2d's default init range
        const std::string p = "layers." + std::to_string(i);
        c.tensors.push_back({p + ".weight", {l.out, in, l.kernel, l.kernel},
                             ngi::test::random_vector(std::size_t(l.out) * in * l.kernel * l.kernel, rng, -bound, bound)});
        if (l.bias) c.tensors.push_back({p + ".bias", {l.out}, ngi::test::random_vector(l.out, rng, -bound, bound)});
        in = l.out;
    }
    return c;
}

// The reference: each layer a zero-padded k x k convolution (stride 1, padding (k - 1) / 2), bias, activation.
std::vector<float> reference_pixel_cnn(const CnnCase& c, std::vector<float> x, int h, int w) {
    int in = c.input_nc;
    std::size_t t = 0;
    for (const CnnLayer& l : c.layers) {
        const std::vector<float>& weight = c.tensors[t++].data;
        const std::vector<float> bias = l.bias ? c.tensors[t++].data : std::vector<float>(l.out, 0.0f);
        int oh = 0, ow = 0;
        x = ngi::ref::conv2d(x, in, h, w, weight, l.out, l.kernel, l.kernel, 1, (l.kernel - 1) / 2,
                             std::vector<float>(l.out, 1.0f), bias, 0, activation_code(l.activation), l.slope, oh, ow);
        REQUIRE((oh == h && ow == w));
        in = l.out;
    }
    return x;
}

}  // namespace

TEST_CASE("pixel_cnn model files match a naive reference over random odd shapes, run and enqueue",
          "[model][pixel_cnn]") {
    std::mt19937 rng(4901);
    const char* const acts[] = {"none", "relu", "leaky_relu", "tanh", "sigmoid"};
    const int kernels[] = {1, 3, 5};
    double worst = 0;
    for (int trial = 0; trial < 8; ++trial) {
        const int input_nc = 1 + 2 * int(rng() % 4);  // 1, 3, 5, 7
        std::vector<CnnLayer> layers;
        const int depth = 1 + int(rng() % 4);
        for (int i = 0; i < depth; ++i)
            layers.push_back({1 + 2 * int(rng() % 5), kernels[rng() % 3], acts[rng() % 5],
                              std::uniform_real_distribution<float>(-0.5f, 0.5f)(rng), rng() % 4 != 0});
        const CnnCase c = random_case(rng, input_nc, layers);
        const int h = 1 + 2 * int(rng() % 10), w = 1 + 2 * int(rng() % 10);  // odd sizes 1..19, 1 x 1 included
        CAPTURE(trial, c.config.dump(), h, w);
        const std::string path = write_pixel_cnn_file("random" + std::to_string(trial), c.tensors, c.config);
        ngi::Model m = ngi::Model::load(ngi::test::device(), path);
        REQUIRE(m.config().family == "pixel_cnn");
        REQUIRE(m.config().input_nc == input_nc);
        REQUIRE(m.config().output_nc == layers.back().out);

        ngi::Tensor x({1, input_nc, h, w});
        x.data = ngi::test::random_vector(x.data.size(), rng);
        ngi::RunInfo info;
        const ngi::Tensor y = m.run(x, &info);
        REQUIRE(y.shape == std::vector<int>{1, layers.back().out, h, w});
        const std::vector<float> want = reference_pixel_cnn(c, x.data, h, w);
        // float32 sums of <= 7 * 25 products of values <= 1 through <= 4 layers against double: 1e-5 is ~50 ulps.
        REQUIRE(ngi::test::worst_ratio(y.data, want, 1e-5, 1e-5) <= 1.0);
        worst = std::max(worst, ngi::test::max_abs_diff(y.data, want));
        REQUIRE(info.sanitized_inputs == 0);
        REQUIRE(info.weight_bytes > 0);

        // Device in, device out: the same bits as run().
        const std::size_t out_bytes = y.data.size() * sizeof(float);
        auto in_buf = ngi::DeviceBuffer::allocate(ngi::test::device(), x.data.size() * sizeof(float));
        auto out_buf = ngi::DeviceBuffer::allocate(ngi::test::device(), out_bytes);
        in_buf.upload(x.data.data(), x.data.size() * sizeof(float));
        m.enqueue(in_buf, out_buf, h, w);
        std::vector<float> got(y.data.size());
        out_buf.download(got.data(), out_bytes);
        REQUIRE(got == y.data);
        REQUIRE(m.sanitized_inputs() == 0);
        fs::remove(path);
    }
    WARN("pixel_cnn: largest |ngi - reference| over 8 random models: " << worst);
}

TEST_CASE("pixel_cnn: NaN and Inf inputs are replaced and counted, and a given input_range bounds them",
          "[model][pixel_cnn][extremes]") {
    std::mt19937 rng(4902);
    CnnCase c = random_case(rng, 3, {{5, 3, "tanh", 0.0f, true}, {2, 1, "none", 0.0f, true}});
    c.config["input_range"] = {-1, 1};
    const std::string path = write_pixel_cnn_file("extremes", c.tensors, c.config);
    ngi::Model m = ngi::Model::load(ngi::test::device(), path);
    ngi::Tensor x({1, 3, 5, 7});
    x.data = ngi::test::random_vector(x.data.size(), rng);
    ngi::Tensor clean = x;
    x.data[0] = NAN;
    x.data[1] = INFINITY;
    x.data[2] = -3e38f;
    clean.data[0] = 0.0f;
    clean.data[1] = 1.0f;
    clean.data[2] = -1.0f;
    ngi::RunInfo info;
    const ngi::Tensor y = m.run(x, &info);
    REQUIRE(info.sanitized_inputs == 3);
    REQUIRE(ngi::test::all_finite(y.data));
    REQUIRE(y.data == m.run(clean).data);
    fs::remove(path);
}

TEST_CASE("pixel_cnn matches PyTorch", "[model][parity][pixel_cnn]") {
    const fs::path dir = ngi::test::python_oracle_data("make_pixel_cnn_parity.py", "pixel_cnn_parity");
    nlohmann::json cases;
    std::ifstream(dir / "cases.json") >> cases;
    REQUIRE(cases.size() >= 3);
    double worst = 0;
    for (const auto& c : cases) {
        CAPTURE(c["name"].get<std::string>());
        ngi::Model m = ngi::Model::load(ngi::test::device(), (dir / c["model"].get<std::string>()).string());
        const ngi::Tensor x = ngi::read_npy((dir / c["input"].get<std::string>()).string());
        const ngi::Tensor want = ngi::read_npy((dir / c["expected"].get<std::string>()).string());
        const ngi::Tensor y = m.run(x);
        REQUIRE(y.shape == want.shape);
        REQUIRE(ngi::test::worst_ratio(y.data, want.data, 1e-5, 1e-5) <= 1.0);
        worst = std::max(worst, ngi::test::max_abs_diff(y.data, want.data));
    }
    WARN("pixel_cnn parity: largest |ngi - PyTorch float64|: " << worst);
}

TEST_CASE("broken pixel_cnn configs and files are refused naming the field or tensor", "[model][file][pixel_cnn]") {
    std::mt19937 rng(4903);
    const CnnCase good = random_case(rng, 3, {{4, 3, "relu", 0.0f, true}, {2, 1, "sigmoid", 0.0f, false}});
    auto parse = [](const nlohmann::json& j) { return ngi::detail::parse_model_config(j.dump(), "p.safetensors"); };
    REQUIRE(parse(good.config).output_nc == 2);
    REQUIRE(parse(good.config).input_range[1] == FLT_MAX);  // no range given: only NaN and Inf are replaced
    auto refused = [&](const std::function<void(nlohmann::json&)>& edit, const std::string& message) {
        nlohmann::json j = good.config;
        edit(j);
        CAPTURE(j.dump());
        CHECK_THROWS_WITH(parse(j), Contains("load model p.safetensors: metadata 'ngi': ") && Contains(message));
    };
    refused([](auto& j) { j.erase("layers"); }, "field 'layers' must be a list of 1..64 layers");
    refused([](auto& j) { j["layers"] = nlohmann::json::array(); }, "field 'layers' must be a list of 1..64 layers");
    refused([](auto& j) { j["layers"][0]["kernel"] = 4; }, "field 'layers[0].kernel' must be an odd integer in 1..31");
    refused([](auto& j) { j["layers"][1]["out"] = 0; }, "field 'layers[1].out' must be an integer in 1..4096");
    refused([](auto& j) { j["layers"][1]["activation"] = "gelu"; },
            "field 'layers[1].activation' must be one of none, relu, leaky_relu, tanh, sigmoid");
    refused([](auto& j) { j["layers"][0]["slope"] = 2; }, "field 'layers[0].slope' must be a number in [-1, 1]");
    refused([](auto& j) { j["layers"][0]["stride"] = 2; }, "'stride' is none of them");
    refused([](auto& j) { j["input_nc"] = 0; }, "field 'input_nc' must be an integer in 1..4096");
    refused([](auto& j) { j["output_nc"] = 3; }, "field 'output_nc' must be the last layer's width (2)");
    refused([](auto& j) { j["output_mode"] = "indirect"; }, "field 'output_mode' must be a string: \"lightmap\"");
    refused([](auto& j) { j["input_range"] = {1, -1}; }, "field 'input_range' must be [lo, hi]");
    refused([](auto& j) { j["required"] = {"dilation"}; },
            "field 'required' lists 'dilation', which this reader does not know: the file needs a newer ngi");
    refused([](auto& j) { j["format_version"] = 2; }, "newer than the newest this reader knows");
    // The registry lists the family with the others.
    refused([](auto& j) { j["family"] = "pixelcnn"; }, "family 'pixelcnn' is not supported (pix2pix_unet, "
                                                       "deepillumination, mlp, voxel_sh, neural_gi, graph, ssgi, pixel_cnn)");

    auto load_error = [&](const std::vector<CnnTensor>& tensors, const std::string& message,
                          const ngi::ModelOptions& options = {}) {
        const std::string path = write_pixel_cnn_file("broken", tensors, good.config);
        CHECK_THROWS_WITH(ngi::Model::load(ngi::test::device(), path, options), Contains(message));
        fs::remove(path);
    };
    auto tensors = good.tensors;  // layers.0.weight, layers.0.bias, layers.1.weight
    tensors.erase(tensors.begin());
    load_error(tensors, "tensor 'layers.0.weight' is missing");
    tensors = good.tensors;
    tensors[2].shape = {2, 4, 3, 3};
    tensors[2].data.resize(2 * 4 * 9);
    load_error(tensors, "tensor 'layers.1.weight' is [2, 4, 3, 3], expected [2, 4, 1, 1]");
    tensors = good.tensors;
    tensors.push_back({"layers.2.weight", {1}, {0.5f}});
    load_error(tensors, "tensor 'layers.2.weight' is not part of this pixel_cnn (2 layers)");
    ngi::ModelOptions options;
    options.bn_mode = "running";
    load_error(good.tensors, "bn_mode, dropout and mlp_path do not apply to family pixel_cnn", options);

    const std::string path = write_pixel_cnn_file("good", good.tensors, good.config);
    ngi::Model m = ngi::Model::load(ngi::test::device(), path);
    CHECK_THROWS_WITH(m.run(ngi::Tensor({1, 4, 5, 5})), Contains("expected [1, 3, H, W] (NCHW, batch 1)"));
    auto small = ngi::DeviceBuffer::allocate(ngi::test::device(), 16);
    auto big = ngi::DeviceBuffer::allocate(ngi::test::device(), 4096);
    CHECK_THROWS_WITH(m.enqueue(small, big, 5, 5), Contains("the input buffer holds 16 bytes, the model needs 300"));
    fs::remove(path);
}
