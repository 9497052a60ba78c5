// Seed 001's AO network (ngi::AoNetwork, kernels/ao.cl): ring gather + per-pixel MLP + clamp/mask against a naive
// C++ reference in double precision, on odd image sizes with background holes and non-finite normals, for the
// seed's radius 0, integer and fractional radii and a ring larger than the image; the device-buffer path equals
// the host path; bad model files and inputs give errors naming them.
#include <cmath>
#include <cstring>
#include <fstream>
#include <random>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "io_test_support.hpp"
#include "ngi/ao.hpp"
#include "ngi/error.hpp"
#include "test_support.hpp"

using Catch::Matchers::Contains;

namespace {

struct Layer {
    int in, out;
    std::vector<float> w, b;
};

// An F32 "mlp" model file with the given layers (tanh hidden, linear last) and config edits.
std::string write_ao_model(const std::string& path, const std::vector<Layer>& layers, nlohmann::json config) {
    nlohmann::json header;
    std::string data;
    auto put = [&](const std::string& name, const std::vector<int>& shape, const std::vector<float>& v) {
        header[name] = {{"dtype", "F32"}, {"shape", shape}, {"data_offsets", {data.size(), data.size() + 4 * v.size()}}};
        data.append(reinterpret_cast<const char*>(v.data()), 4 * v.size());
    };
    nlohmann::json spec = nlohmann::json::array();
    for (std::size_t i = 0; i < layers.size(); ++i) {
        put("layers." + std::to_string(i) + ".weight", {layers[i].out, layers[i].in}, layers[i].w);
        put("layers." + std::to_string(i) + ".bias", {layers[i].out}, layers[i].b);
        spec.push_back({{"out", layers[i].out}, {"activation", i + 1 < layers.size() ? "tanh" : "none"}});
    }
    config["family"] = "mlp";
    config["layers"] = spec;
    header["__metadata__"] = {{"ngi", config.dump()}};
    std::string h = header.dump();
    while (h.size() % 8) h += ' ';
    std::string bytes(8, '\0');
    for (int i = 0; i < 8; ++i) bytes[i] = char((std::uint64_t(h.size()) >> (8 * i)) & 0xff);
    bytes += h + data;
    std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    return path;
}

std::vector<Layer> random_layers(std::mt19937& rng, const std::vector<int>& widths) {
    std::vector<Layer> l;
    for (std::size_t i = 0; i + 1 < widths.size(); ++i) {
        const float bound = 1.5f / std::sqrt(float(widths[i]));
        l.push_back({widths[i], widths[i + 1], ngi::test::random_vector(std::size_t(widths[i]) * widths[i + 1], rng, -bound, bound),
                     ngi::test::random_vector(std::size_t(widths[i + 1]), rng, -0.5f, 1.0f)});
    }
    return l;
}

bool surface(float x, float y, float z) { return x != 0.0f || y != 0.0f || z != 0.0f; }
// The model's input guard for input_range [-1, 1] (ModelConfig::input_range): NaN -> 0, +-Inf -> +-1.
double guarded(float v) { return std::isnan(v) ? 0.0 : std::clamp(double(v), -1.0, 1.0); }

// Naive reference: ring gather (CONVENTIONS section 15), the MLP in double, clamp, background 1.
ngi::Image reference_ao(const ngi::Image& n, const std::vector<Layer>& layers, float radius) {
    const std::vector<int> off = ngi::AoNetwork::ring_offsets(radius);
    ngi::Image out(n.width, n.height, 1);
    for (int y = 0; y < n.height; ++y)
        for (int x = 0; x < n.width; ++x) {
            const float cx = n.at(0, y, x), cy = n.at(1, y, x), cz = n.at(2, y, x);
            if (!surface(cx, cy, cz)) {
                out.at(0, y, x) = 1.0f;
                continue;
            }
            std::vector<double> h;
            for (int k = 0; k < 16; ++k) {
                const int r = y + off[2 * k], c = x + off[2 * k + 1];
                float v[3] = {cx, cy, cz};
                if (r >= 0 && r < n.height && c >= 0 && c < n.width && surface(n.at(0, r, c), n.at(1, r, c), n.at(2, r, c)))
                    for (int i = 0; i < 3; ++i) v[i] = n.at(i, r, c);
                for (float e : v) h.push_back(guarded(e));
            }
            for (std::size_t li = 0; li < layers.size(); ++li) {
                const Layer& L = layers[li];
                std::vector<double> o(std::size_t(L.out));
                for (int j = 0; j < L.out; ++j) {
                    double s = L.b[j];
                    for (int i = 0; i < L.in; ++i) s += double(L.w[std::size_t(j) * L.in + i]) * h[i];
                    o[j] = li + 1 < layers.size() ? std::tanh(s) : s;
                }
                h = o;
            }
            out.at(0, y, x) = float(std::clamp(h[0], 0.0, 1.0));
        }
    return out;
}

}  // namespace

TEST_CASE("AO ring offsets: 16 points, rounded half away from zero, counter-clockwise from the right",
          "[ao][mlp]") {
    const std::vector<int> o = ngi::AoNetwork::ring_offsets(3.0f);
    REQUIRE(o.size() == 32);
    CHECK((o[0] == 0 && o[1] == 3));     // k = 0: right
    CHECK((o[8] == -3 && o[9] == 0));    // k = 4: up (smaller row)
    CHECK((o[4] == -2 && o[5] == 2));    // k = 2: 3 / sqrt(2) = 2.12 -> 2
    CHECK((o[16] == 0 && o[17] == -3));  // k = 8: left
    for (int v : ngi::AoNetwork::ring_offsets(0.0f)) CHECK(v == 0);
    CHECK(ngi::AoNetwork::ring_offsets(2.5f)[1] == 3);  // 2.5 -> 3 (half away from zero)
}

TEST_CASE("AO network: ring gather + MLP + clamp match a naive reference, device path equals host path",
          "[ao][mlp]") {
    ngi::test::TempDir dir("ao-network");
    std::mt19937 rng(11);
    const std::vector<Layer> layers = random_layers(rng, {48, 7, 5, 1});  // odd widths
    const nlohmann::json ao_meta = {{"neighbours", 16}, {"radius_px", 3.0}, {"at_size", 64}};
    const std::string path = write_ao_model(dir / "ao.safetensors", layers, {{"input_nc", 48}, {"input_range", {-1, 1}}, {"ao", ao_meta}});
    for (const char* mlp_path : {"fused", "dense"}) {
        ngi::ModelOptions opt;
        opt.mlp_path = mlp_path;
        ngi::AoNetwork net = ngi::AoNetwork::load(ngi::test::device(), path, opt);
        CHECK(net.trained_radius_px() == 3.0f);
        CHECK(net.trained_size() == 64);
        CHECK(net.normals() == "smooth");
        CHECK(net.radius_for(128) == 6.0f);
        for (auto [w, h] : {std::pair{37, 29}, std::pair{1, 1}, std::pair{64, 3}}) {
            ngi::Image n(w, h, 3);
            std::uniform_real_distribution<float> u(-1.0f, 1.0f), p(0.0f, 1.0f);
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    if (p(rng) < 0.25f) continue;  // background hole
                    glm::vec3 v(u(rng), u(rng), u(rng));
                    v = glm::normalize(v + glm::vec3(0, 0, 0.01f));
                    for (int c = 0; c < 3; ++c) n.at(c, y, x) = v[c];
                }
            if (w * h > 10) {
                n.at(1, h / 2, w / 2) = NAN;  // non-finite normals are sanitized like any model input
                n.at(0, 1, 1) = INFINITY;
            }
            for (float radius : {0.0f, 3.0f, 2.6f, 80.0f}) {
                CAPTURE(mlp_path, w, h, radius);
                ngi::RunInfo info;
                const ngi::Image got = net.run(n, radius, &info);
                const ngi::Image want = reference_ao(n, layers, radius);
                REQUIRE(got.channels == 1);
                // float32 sums of 48 products of O(1) terms through two tanh layers: ~1e-6 observed.
                CHECK(ngi::test::max_abs_diff(got.data, want.data) < 2e-5);
                for (float v : got.data) REQUIRE((v >= 0.0f && v <= 1.0f));
                if (w * h > 10) CHECK(info.sanitized_inputs > 0);
            }
            // Device in, device out: the same bits as run() (radius < 0: the model's, scaled to the height).
            ngi::DeviceBuffer in = ngi::DeviceBuffer::allocate(ngi::test::device(), n.data.size() * 4);
            ngi::DeviceBuffer out = ngi::DeviceBuffer::allocate(ngi::test::device(), n.plane() * 4);
            in.upload(n.data.data(), n.data.size() * 4);
            net.enqueue(in, out, h, w);
            std::vector<float> dev(n.plane());
            out.download(dev.data(), dev.size() * 4);
            const std::vector<float> whole = net.run(n, net.radius_for(h)).data;
            CHECK(dev == whole);
            // In bands of rows (one row; two rows and a remainder; more than the image): the same bits.
            for (std::size_t band : {std::size_t(1), std::size_t(2 * w + 1), std::size_t(w * h + 7)}) {
                CAPTURE(band);
                net.set_band_pixels(band);
                CHECK(net.band_pixels() == band);
                CHECK(net.run(n, net.radius_for(h)).data == whole);
            }
            net.set_band_pixels(ngi::AoNetwork::kDefaultBandPixels);
        }
    }
}

TEST_CASE("AO network: bad models and inputs give errors naming them", "[ao][mlp]") {
    ngi::test::TempDir dir("ao-bad");
    std::mt19937 rng(3);
    const nlohmann::json ao_meta = {{"neighbours", 16}, {"radius_px", 3.0}, {"at_size", 64}};
    const auto good = random_layers(rng, {48, 4, 1});
    auto load = [&](const std::string& p) { return ngi::AoNetwork::load(ngi::test::device(), p); };
    CHECK_THROWS_WITH(load(write_ao_model(dir / "no_ao.safetensors", good, {{"input_nc", 48}})),
                      Contains("no_ao.safetensors") && Contains("no \"ao\" object"));
    CHECK_THROWS_WITH(load(write_ao_model(dir / "in3.safetensors", random_layers(rng, {3, 4, 1}),
                                          {{"input_nc", 3}, {"ao", ao_meta}})),
                      Contains("in3.safetensors") && Contains("expected 48"));
    CHECK_THROWS_WITH(load(write_ao_model(dir / "out2.safetensors", random_layers(rng, {48, 4, 2}),
                                          {{"input_nc", 48}, {"ao", ao_meta}})),
                      Contains("expected 1"));
    nlohmann::json bad = ao_meta;
    bad["radius_px"] = -2;
    CHECK_THROWS_WITH(load(write_ao_model(dir / "radius.safetensors", good, {{"input_nc", 48}, {"ao", bad}})),
                      Contains("ao.radius_px"));
    bad = ao_meta;
    bad["normals"] = "bent";
    CHECK_THROWS_WITH(load(write_ao_model(dir / "kind.safetensors", good, {{"input_nc", 48}, {"ao", bad}})),
                      Contains("ao.normals"));
    bad = ao_meta;
    bad["neighbours"] = 8;
    CHECK_THROWS_WITH(load(write_ao_model(dir / "ring.safetensors", good, {{"input_nc", 48}, {"ao", bad}})),
                      Contains("ao.neighbours"));
    ngi::AoNetwork net = load(write_ao_model(dir / "ok.safetensors", good, {{"input_nc", 48}, {"ao", ao_meta}}));
    CHECK_THROWS_WITH(net.run(ngi::Image(4, 4, 4)), Contains("ok.safetensors") && Contains("4 channels"));
    CHECK_THROWS_WITH(net.run(ngi::Image(4, 4, 3), NAN), Contains("ring radius"));
    ngi::DeviceBuffer small = ngi::DeviceBuffer::allocate(ngi::test::device(), 16);
    CHECK_THROWS_WITH(net.enqueue(small, small, 4, 4), Contains("normals buffer"));
}

TEST_CASE("AO network on a tiny image (ring gather, shape-specialized MLP, clamp)", "[ao][mlp][oclgrind]") {
    ngi::test::TempDir dir("ao-tiny");
    std::mt19937 rng(5);
    const std::vector<Layer> layers = random_layers(rng, {48, 5, 3, 1});
    const nlohmann::json ao_meta = {{"neighbours", 16}, {"radius_px", 2.0}, {"at_size", 5}};
    ngi::AoNetwork net = ngi::AoNetwork::load(
        ngi::test::device(),
        write_ao_model(dir / "tiny.safetensors", layers, {{"input_nc", 48}, {"input_range", {-1, 1}}, {"ao", ao_meta}}));
    ngi::Image n(7, 5, 3);
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 7; ++x)
            if ((x + y) % 4 != 0)
                for (int c = 0; c < 3; ++c) n.at(c, y, x) = c == (x % 3) ? 1.0f : 0.0f;
    const ngi::Image got = net.run(n);
    CHECK(ngi::test::max_abs_diff(got.data, reference_ao(n, layers, 2.0f).data) < 2e-5);
    net.set_band_pixels(10);  // bands of one row (7 pixels wide): every kernel on a partial image, same bits
    CHECK(net.run(n).data == got.data);
    CHECK_THROWS_WITH(net.set_band_pixels(0), Contains("band size"));
}
