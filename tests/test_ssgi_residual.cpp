// Output mode "ssgi_residual" (issue 45; docs/CONVENTIONS.md section 8): a pix2pix generator that corrects the SSGI
// rung. Its input is the front view and the rung's indirect light encoded like a target; its output is added to
// that encoding before decoding. Checked here against the pieces it is made of: the single-view input, the ssgi
// rung's own lightmap, Model::run and a naive C++ decode. (Its PyTorch parity: training/tests/test_training.py.)
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include <nlohmann/json.hpp>

#include "ngi.h"
#include "ngi/device_buffer.hpp"
#include "ngi/error.hpp"
#include "ngi/model.hpp"
#include "ngi/pipeline.hpp"
#include "test_support.hpp"

using namespace ngi;
using Catch::Matchers::Contains;

namespace {

const std::string kSsgiRung = std::string(NGI_SOURCE_DIR) + "/models/ssgi/ssgi_surround.safetensors";

// A pix2pix U-Net file (num_downs 5, ngf 2, 13 -> 3 channels) with random weights, or with a last layer of zeros
// (`zero_output`: tanh(0) = 0, the network corrects nothing). `edit` may change the config before it is written.
std::string write_unet(const std::string& stem, std::uint32_t seed, bool zero_output,
                       const std::function<void(nlohmann::json&)>& edit = {}) {
    std::mt19937 rng(seed);
    const int ngf = 2, in = 13, out = 3;
    nlohmann::json header;
    std::string data;
    auto add = [&](const std::string& name, std::vector<int> shape, float lo, float hi) {
        std::size_t n = 1;
        for (int d : shape) n *= std::size_t(d);
        const std::vector<float> v = test::random_vector(n, rng, lo, hi);
        header[name] = {{"dtype", "F32"}, {"shape", shape}, {"data_offsets", {data.size(), data.size() + 4 * n}}};
        data.append(reinterpret_cast<const char*>(v.data()), 4 * n);
    };
    auto bn = [&](const std::string& p, int c) {
        add(p + ".weight", {c}, 0.5f, 1.5f);
        add(p + ".bias", {c}, -0.2f, 0.2f);
        add(p + ".running_mean", {c}, -0.2f, 0.2f);
        add(p + ".running_var", {c}, 0.5f, 2.0f);
    };
    add("model.model.0.weight", {ngf, in, 4, 4}, -0.2f, 0.2f);
    const float w = zero_output ? 0.0f : 0.2f;
    add("model.model.3.weight", {2 * ngf, out, 4, 4}, -w, w);
    add("model.model.3.bias", {out}, -w / 4, w / 4);
    const int ch[5] = {ngf, 2 * ngf, 4 * ngf, 8 * ngf, 8 * ngf};
    std::string seq = "model.model.1.model";
    for (int i = 1; i <= 3; ++i) {
        add(seq + ".1.weight", {ch[i], ch[i - 1], 4, 4}, -0.2f, 0.2f);
        bn(seq + ".2", ch[i]);
        add(seq + ".5.weight", {2 * ch[i], ch[i - 1], 4, 4}, -0.2f, 0.2f);
        bn(seq + ".6", ch[i - 1]);
        seq += ".3.model";
    }
    add(seq + ".1.weight", {ch[4], ch[3], 4, 4}, -0.2f, 0.2f);
    add(seq + ".3.weight", {ch[4], ch[3], 4, 4}, -0.2f, 0.2f);
    bn(seq + ".4", ch[3]);
    // The gather of the shipped rung (its file's settings), as training's export copies them.
    const nlohmann::json rung = nlohmann::json::parse(Model::load(test::device(), kSsgiRung).config().json);
    nlohmann::json gather;
    for (const char* k :
         {"view", "cluster_level", "bounces", "near_factor", "min_distance", "visibility_steps", "thickness"})
        if (rung.contains(k)) gather[k] = rung[k];
    nlohmann::json config = {{"family", "pix2pix_unet"}, {"input_nc", in}, {"output_nc", out}, {"ngf", ngf},
                             {"num_downs", 5}, {"bn_mode", "running"}, {"output_mode", "ssgi_residual"},
                             {"required", {"output_mode", "ssgi"}}, {"ssgi", gather},
                             {"input_layout", ssgi_residual_input_channels()}};
    if (edit) edit(config);
    header["__metadata__"] = {{"ngi", config.dump()}};
    std::string h = header.dump();
    while (h.size() % 8) h += ' ';
    std::string bytes(8, '\0');
    for (int i = 0; i < 8; ++i) bytes[i] = char((std::uint64_t(h.size()) >> (8 * i)) & 0xff);
    bytes += h + data;
    const auto p = std::filesystem::temp_directory_path() / ("ngi_test_residual_" + stem + ".safetensors");
    std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    return p.string();
}

// A six-face frame with plausible values, emission on, and hostile direct light at a few front pixels.
Frame random_frame(int n, std::mt19937& rng) {
    Frame fr;
    fr.n = n;
    fr.look = glm::normalize(glm::vec3(0.2f, -0.3f, -1.0f));
    fr.up = glm::vec3(0, 1, 0);
    for (int f = 0; f < kFaceCount; ++f) {
        auto img = [&](int c, float lo, float hi) {
            Image im(n, n, c);
            im.data = test::random_vector(im.data.size(), rng, lo, hi);
            return im;
        };
        fr.get(Feature::Albedo, Face(f)) = img(3, 0.0f, 1.0f);
        fr.get(Feature::Normal, Face(f)) = img(3, -1.0f, 1.0f);
        fr.get(Feature::Depth, Face(f)) = img(1, 0.5f, 20.0f);
        fr.get(Feature::Direct, Face(f)) = img(3, 0.0f, 3.0f);
        fr.get(Feature::Emission, Face(f)) = img(3, 0.0f, 0.3f);
    }
    std::vector<float>& d = fr.get(Feature::Direct, Face::Front).data;
    const float hostile[] = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), -2.0f,
                             70000.0f, FLT_MAX};
    for (std::size_t k = 0; k < std::size(hostile); ++k) d[(k * 797 + 5) % d.size()] = hostile[k];
    return fr;
}

float clean(float v) { return std::isnan(v) ? 0.0f : std::clamp(v, 0.0f, FLT_MAX); }

// compose.cl decode_light for [-1, 1] and the Reinhard transfer.
float decode(float v) {
    float y = (v + 1.0f) / 2.0f;
    y = std::isnan(y) ? 0.0f : std::clamp(y, 0.0f, 1.0f);
    return y < 1.0f ? std::fmin(y / (1.0f - y), 65504.0f) : 65504.0f;
}

}  // namespace

TEST_CASE("ssgi_residual: the lightmap is decode(network + its SSGI channels) + direct, and a zero network gives "
          "the SSGI rung's lightmap", "[ssgi][residual]") {
    Device& dev = test::device();
    std::mt19937 rng(45);
    const int n = 32;
    const std::size_t plane = std::size_t(n) * n;
    Model rung = Model::load(dev, kSsgiRung);
    Model net = Model::load(dev, write_unet("random", 1, false));
    Model zero = Model::load(dev, write_unet("zero", 2, true));
    REQUIRE(net.config().output_mode == "ssgi_residual");
    REQUIRE(net.config().ssgi.cluster_level == rung.config().ssgi.cluster_level);
    SurroundPipeline pl(dev, n);
    const Frame fr = random_frame(n, rng);
    const std::vector<float>& direct = fr.get(Feature::Direct, Face::Front).data;

    const FrameImages s = pl.run(rung, fr, true, false, false);
    // The input: the single-view channels bit for bit, then the rung's indirect light encoded as a target.
    const Tensor x = pl.network_input(fr, net.config());
    REQUIRE(x.shape == std::vector<int>{1, 13, n, n});
    ModelConfig single;
    single.input_nc = 10;
    const Tensor x10 = pl.network_input(fr, single);
    REQUIRE(std::equal(x10.data.begin(), x10.data.end(), x.data.begin()));
    for (std::size_t i = 0; i < 3 * plane; ++i) {
        const float ind = std::max(clean(s.lightmap.data[i]) - clean(direct[i]), 0.0f);
        REQUIRE(x.data[10 * plane + i] == Approx(-1.0f + 2.0f * std::min(ind / (1.0f + ind), 1.0f)).margin(1e-6));
    }

    // A network that corrects nothing: the rung's lightmap, up to the encode/decode round trip (float rounding of
    // y = s / (1 + s) and back, relative 1e-6 / (1 - y); s here stays below ~30 but near the hostile pixels, so 1e-4
    // is ample), except that the encoded domain stops at 65504 (LIGHT_MAX), as every decoded output does: the
    // pixels next to the FLT_MAX direct light get 1e23 of indirect light from the rung and 65504 here.
    const FrameImages z = pl.run(zero, fr, true, false, false);
    int saturated = 0;
    for (std::size_t i = 0; i < 3 * plane; ++i) {
        const float d = clean(direct[i]), ind = std::max(clean(s.lightmap.data[i]) - d, 0.0f);
        saturated += ind > 65504.0f;
        REQUIRE(std::isfinite(z.lightmap.data[i]));
        REQUIRE(z.lightmap.data[i] == Approx(std::fmin(d + std::fmin(ind, 65504.0f), FLT_MAX)).epsilon(1e-4).margin(1e-6));
    }
    CHECK(saturated > 0);  // the hostile pixels did reach the cap

    // A random network: Model::run on that input, then the decode written out here.
    const Tensor y = net.run(x);
    const FrameImages r = pl.run(net, fr, true, true, false);
    double worst = 0;
    for (std::size_t i = 0; i < 3 * plane; ++i) {
        const float want = std::fmin(decode(y.data[i] + x.data[10 * plane + i]) + clean(direct[i]), FLT_MAX);
        REQUIRE(std::isfinite(r.lightmap.data[i]));
        REQUIRE(r.lightmap.data[i] == Approx(want).epsilon(1e-5).margin(1e-6));
        worst = std::max(worst, double(std::abs(r.lightmap.data[i] - want)) / std::max(1e-3f, std::abs(want)));
    }
    WARN("ssgi_residual lightmap vs Model::run + naive decode: worst relative difference " << worst);
    REQUIRE(r.final_image.data == pl.compose(r.lightmap, fr).data);

    // Device in, device out: the same lightmap bit for bit.
    const std::vector<float> planes = pack_frame_planes(fr, 6);
    DeviceBuffer in = DeviceBuffer::allocate(dev, planes.size() * sizeof(float));
    in.upload(planes.data(), in.bytes());
    FrameOutputs outs;
    outs.lightmap = DeviceBuffer::allocate(dev, 3 * plane * sizeof(float));
    pl.enqueue(net, in, FrameDesc::of(fr, 6), outs);
    std::vector<float> got(3 * plane);
    outs.lightmap.download(got.data(), got.size() * sizeof(float));
    REQUIRE(got == r.lightmap.data);

    // What needs the SSGI estimate refuses the paths without it.
    REQUIRE_THROWS_WITH(pl.front_lightmap(y, net.config(), fr), Contains("ssgi_residual") && Contains("run it on frames"));
    const std::vector<float> front = pack_frame_planes(fr, 1);
    DeviceBuffer one = DeviceBuffer::allocate(dev, front.size() * sizeof(float));
    one.upload(front.data(), one.bytes());
    REQUIRE_THROWS_WITH(pl.enqueue(net, one, FrameDesc::of(fr, 1), outs),
                        Contains("corrects the SSGI rung") && Contains("all 6 faces"));
}

TEST_CASE("ssgi_residual: the file's rules name the field", "[ssgi][residual][model]") {
    Device& dev = test::device();
    auto error = [&](const std::string& stem, const std::function<void(nlohmann::json&)>& edit) {
        try {
            Model::load(dev, write_unet(stem, 3, false, edit));
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    CHECK(error("ok", {}).empty());
    // The C ABI names the mode (an application decoding outputs itself must not take it for a lightmap).
    const char* spec = std::getenv("NGI_TEST_DEVICE");
    ngi_device* cdev = nullptr;
    ngi_model* cm = nullptr;
    REQUIRE(ngi_device_open(spec ? spec : "cpu", &cdev) == NGI_OK);
    REQUIRE(ngi_model_load(cdev, write_unet("c_abi", 4, false).c_str(), &cm) == NGI_OK);
    ngi_output_mode mode = NGI_OUTPUT_LIGHTMAP;
    CHECK(ngi_model_output_mode(cm, &mode) == NGI_OK);
    CHECK(mode == NGI_OUTPUT_SSGI_RESIDUAL);
    CHECK(ngi_model_release(cm) == NGI_OK);
    CHECK(ngi_device_release(cdev) == NGI_OK);
    CHECK_THAT(error("no_ssgi", [](nlohmann::json& c) { c.erase("ssgi"); }),
               Contains("'ssgi'") && Contains("ssgi_residual"));
    CHECK_THAT(error("ssgi_type", [](nlohmann::json& c) { c["ssgi"] = 3; }), Contains("'ssgi' must be an object"));
    CHECK_THAT(error("ssgi_key", [](nlohmann::json& c) { c["ssgi"]["radius"] = 2; }),
               Contains("'radius'") && Contains("not a setting of the gather"));
    CHECK_THAT(error("ssgi_range", [](nlohmann::json& c) { c["ssgi"]["bounces"] = 99; }),
               Contains("'ssgi': field 'bounces'"));
    CHECK_THAT(error("ranges", [](nlohmann::json& c) { c["output_range"] = {-2, 2}; }),
               Contains("input_range and output_range must be equal"));
    CHECK_THAT(error("other_mode", [](nlohmann::json& c) { c["output_mode"] = "indirect"; }),
               Contains("field 'ssgi' is only read with output_mode \"ssgi_residual\""));
}
