// The loader's fusion of family "graph" node lists (models/graph_fuse.hpp, docs/MODEL_FORMAT.md "graph"): a file that
// describes the network as ONNX does (affine and activation nodes of their own) loads to the node list the converter
// used to write (affines folded into the layer's weights and bias, activations into its epilogue, ReLUs into the
// gathers of the convolutions reading them), and runs to the same output as that fused file; what must not fold (a
// producer with two readers, the graph output, a reader that is no convolution, a slope that would change) does not.
// Every case compares the network loaded from the unfused file with the fused file as the converter wrote it, and
// checks what the pass folded (fuse_graph's counts and node labels).
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>

#include "models/graph_fuse.hpp"
#include "ngi/model.hpp"
#include "reference.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using nlohmann::json;
using ngi::test::Tol;

namespace {

struct FuseTensor {
    std::vector<int> shape;
    std::vector<float> data;
};
using FuseTensors = std::map<std::string, FuseTensor>;

json fuse_config(int input_nc, const std::string& output, const json& nodes, const std::string& layout = "nchw") {
    return {{"format_version", 1}, {"family", "graph"}, {"input_nc", input_nc},
            {"graph", {{"layout", layout}, {"input", "x"}, {"output", output}, {"nodes", nodes}}}};
}

// A safetensors file of `tensors` (F32) with `config` as __metadata__["ngi"], in the temporary folder.
std::string write_fuse_file(const std::string& stem, const FuseTensors& tensors, const json& config) {
    json header;
    std::string data;
    for (const auto& [name, t] : tensors) {
        header[name] = {{"dtype", "F32"}, {"shape", t.shape},
                        {"data_offsets", {data.size(), data.size() + 4 * t.data.size()}}};
        data.append(reinterpret_cast<const char*>(t.data.data()), 4 * t.data.size());
    }
    header["__metadata__"] = {{"ngi", config.dump()}};
    std::string h = header.dump();
    h.append((8 - h.size() % 8) % 8, ' ');
    const fs::path path = fs::temp_directory_path() / ("ngi_test_graph_fuse_" + stem + ".safetensors");
    std::ofstream out(path, std::ios::binary);
    const std::uint64_t n = h.size();
    out.write(reinterpret_cast<const char*>(&n), 8);
    out << h << data;
    return path.string();
}

// What the loader's pass makes of a file's node list: the counts and each remaining node's label and fields.
struct FuseSummary {
    int affines = 0, activations = 0, input_activations = 0;
    std::vector<std::string> labels;
    std::vector<json> fields;
};
FuseSummary fuse_summary(const json& config, const FuseTensors& tensors) {
    using namespace ngi::detail;
    const GraphDesc d = parse_graph_desc(config, "test: ");
    SafetensorsFile file;
    for (const auto& [name, t] : tensors) file.tensors[name] = StoredTensor{t.shape, "F32", t.data};
    const FusedGraph f = fuse_graph(d, check_graph_weights(d, file));
    FuseSummary s{f.affines, f.activations, f.input_activations, {}, {}};
    for (const GraphNodeDesc& n : f.desc.nodes) {
        s.labels.push_back(graph_node_label(n));
        s.fields.push_back(n.fields);
    }
    return s;
}

std::vector<float> run_fuse_file(const std::string& path, const ngi::Tensor& x) {
    return ngi::Model::load(ngi::test::device(), path).run(x).data;
}

std::vector<float> abs_of(std::vector<float> v) {
    for (float& x : v) x = std::abs(x);
    return v;
}

// A batch norm of c channels in double, as an exporter's running statistics: scale = gamma / sqrt(var + eps),
// shift = beta - mean * scale.
struct FuseBatchNorm {
    std::vector<double> scale, shift;
};
FuseBatchNorm random_batch_norm(int c, std::mt19937& rng) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    FuseBatchNorm bn;
    for (int i = 0; i < c; ++i) {
        const double gamma = 0.5 + u(rng), beta = u(rng) - 0.5, mean = 0.4 * (u(rng) - 0.5), var = 0.2 + u(rng);
        bn.scale.push_back(gamma / std::sqrt(var + 1e-5));
        bn.shift.push_back(beta - mean * bn.scale.back());
    }
    return bn;
}
std::vector<float> to_float(const std::vector<double>& v) { return {v.begin(), v.end()}; }

// The converter's fold (bindings/python/ngi/onnx_import.py before issue 49): weights times the scale per output
// channel (`inner` consecutive values a channel, every `period` channels) and bias * scale + shift, in double with
// the scale and shift it computed in double, rounded to float32 once.
void converter_fold(FuseTensor& w, FuseTensor& b, const std::vector<double>& scale, const std::vector<double>& shift,
                    std::size_t inner, std::size_t period) {
    for (std::size_t i = 0; i < w.data.size(); ++i) w.data[i] = float(double(w.data[i]) * scale[(i / inner) % period]);
    if (b.data.empty()) b = {{int(scale.size())}, std::vector<float>(scale.size(), 0.0f)};
    for (std::size_t c = 0; c < scale.size(); ++c) b.data[c] = float(double(b.data[c]) * scale[c] + shift[c]);
}

}  // namespace

TEST_CASE("graph fusion at load: conv, batch norm, relu, conv, conv_transpose, scale, tanh as the fused file",
          "[model][graph][fuse]") {
    std::mt19937 rng(4901);
    const int C0 = 3, C1 = 5, C2 = 6, C3 = 4, H = 9, W = 11;
    auto rnd = [&](std::vector<int> shape) {
        std::size_t n = 1;
        for (int s : shape) n *= std::size_t(s);
        return FuseTensor{shape, ngi::test::random_vector(n, rng, -0.5f, 0.5f)};
    };
    FuseTensors t = {{"c1.w", rnd({C1, C0, 3, 3})}, {"c1.b", rnd({C1})}, {"c2.w", rnd({C2, C1, 3, 3})},
                     {"c2.b", rnd({C2})},          {"c3.w", rnd({C2, C3, 4, 4})}};
    const FuseBatchNorm bn = random_batch_norm(C1, rng);
    std::vector<double> s3(C3);
    for (double& v : s3) v = double(std::uniform_real_distribution<float>(0.5f, 2.0f)(rng));  // a Mul by float32s
    // The file as ONNX describes the network: the batch norm's scale and shift stored as float32.
    FuseTensors unfused = t;
    unfused["bn1.s"] = {{C1}, to_float(bn.scale)};
    unfused["bn1.t"] = {{C1}, to_float(bn.shift)};
    unfused["m3.s"] = {{C3}, to_float(s3)};
    const json conv1 = {{"name", "c1"}, {"op", "conv2d"}, {"inputs", {"x"}}, {"output", "t1"}, {"in", C0}, {"out", C1},
                        {"kernel", {3, 3}}, {"stride", 1}, {"pad", 1}, {"weight", "c1.w"}, {"bias", "c1.b"}};
    const json conv2 = {{"name", "c2"}, {"op", "conv2d"}, {"inputs", {"t3"}}, {"output", "t4"}, {"in", C1}, {"out", C2},
                        {"kernel", {3, 3}}, {"stride", 2}, {"pad", 1}, {"weight", "c2.w"}, {"bias", "c2.b"}};
    const json conv3 = {{"name", "c3"}, {"op", "conv_transpose2d"}, {"inputs", {"t4"}}, {"output", "t5"}, {"in", C2},
                        {"out", C3}, {"kernel", {4, 4}}, {"stride", 2}, {"pad", 1}, {"weight", "c3.w"}};
    const json nodes = {
        conv1,
        {{"name", "bn1"}, {"op", "affine"}, {"inputs", {"t1"}}, {"output", "t2"}, {"scale", "bn1.s"},
         {"shift", "bn1.t"}},
        {{"name", "r1"}, {"op", "activation"}, {"inputs", {"t2"}}, {"output", "t3"}, {"activation", "relu"}},
        conv2,
        conv3,
        {{"name", "m3"}, {"op", "affine"}, {"inputs", {"t5"}}, {"output", "t6"}, {"scale", "m3.s"}},
        {{"name", "th"}, {"op", "activation"}, {"inputs", {"t6"}}, {"output", "y"}, {"activation", "tanh"}}};
    const json unfused_cfg = fuse_config(C0, "y", nodes);
    // The file the converter wrote: the same network fused.
    FuseTensors fused = t;
    converter_fold(fused["c1.w"], fused["c1.b"], bn.scale, bn.shift, 9 * C0, C1);
    converter_fold(fused["c3.w"], fused["c3.b"], s3, std::vector<double>(C3, 0.0), 16, C3);
    json f1 = conv1, f2 = conv2, f3 = conv3;
    f1["output"] = "t3";
    f1["activation"] = "relu";
    f3["output"] = "y";
    f3["bias"] = "c3.b";
    f3["activation"] = "tanh";
    const json fused_cfg = fuse_config(C0, "y", {f1, f2, f3});

    const FuseSummary s = fuse_summary(unfused_cfg, unfused);
    CHECK(s.affines == 2);
    CHECK(s.activations == 2);
    CHECK(s.input_activations == 0);
    CHECK(s.labels == std::vector<std::string>{"c1 + bn1 + r1", "c2", "c3 + m3 + th"});
    CHECK(s.fields[0]["activation"] == "relu");
    CHECK(s.fields[2]["activation"] == "tanh");
    // A file the converter fused is the pass's fixed point: nothing folds (it loads as it always did).
    const FuseSummary again = fuse_summary(fused_cfg, fused);
    CHECK(again.affines + again.activations + again.input_activations == 0);
    CHECK(again.labels == std::vector<std::string>{"c1", "c2", "c3"});

    ngi::Tensor x({1, C0, H, W});
    x.data = ngi::test::random_vector(x.data.size(), rng);
    const std::vector<float> got = run_fuse_file(write_fuse_file("chain_unfused", unfused, unfused_cfg), x);
    const std::vector<float> want = run_fuse_file(write_fuse_file("chain_fused", fused, fused_cfg), x);
    // The network as written in double (each layer's output rounded to float32), and its terms' magnitudes: the same
    // chain on absolute values without activations (relu and tanh are 1-Lipschitz).
    std::vector<float> sh1(C1), ash1(C1);
    for (int c = 0; c < C1; ++c) {
        sh1[c] = float(double(t["c1.b"].data[c]) * double(float(bn.scale[c])) + double(float(bn.shift[c])));
        ash1[c] = std::abs(t["c1.b"].data[c] * float(bn.scale[c])) + std::abs(float(bn.shift[c]));
    }
    int h1 = 0, w1 = 0, h2 = 0, w2 = 0, h3 = 0, w3 = 0;
    const std::vector<float> one2(C2, 1.0f), zero3(C3, 0.0f);
    std::vector<float> r = ngi::ref::conv2d(x.data, C0, H, W, t["c1.w"].data, C1, 3, 3, 1, 1, to_float(bn.scale), sh1,
                                            0, 1, 0.0, h1, w1);
    r = ngi::ref::conv2d(r, C1, h1, w1, t["c2.w"].data, C2, 3, 3, 2, 1, one2, t["c2.b"].data, 0, 0, 0.0, h2, w2);
    r = ngi::ref::conv_transpose2d(r, C2, h2, w2, t["c3.w"].data, C3, 4, 4, 2, 1, to_float(s3), zero3, 0, 3, 0.0, h3,
                                   w3);
    std::vector<float> a = ngi::ref::conv2d(abs_of(x.data), C0, H, W, abs_of(t["c1.w"].data), C1, 3, 3, 1, 1,
                                            abs_of(to_float(bn.scale)), ash1, 0, 0, 0.0, h1, w1);
    a = ngi::ref::conv2d(a, C1, h1, w1, abs_of(t["c2.w"].data), C2, 3, 3, 2, 1, one2, abs_of(t["c2.b"].data), 0, 0,
                         0.0, h2, w2);
    a = ngi::ref::conv_transpose2d(a, C2, h2, w2, abs_of(t["c3.w"].data), C3, 4, 4, 2, 1, abs_of(to_float(s3)), zero3,
                                   0, 0, 0.0, h3, w3);
    REQUIRE(got.size() == r.size());
    const std::vector<double> mag(a.begin(), a.end());
    // Roundings per output on the way, each side: the three dot products (27 + 45 + 24 terms: products and sums),
    // bias, scale and shift (3 each), the folded weights' own (2 a term: the scale's float32 rounding in the file,
    // the product's), the built-in tanh (5 ulp <= 10 u of S); the two evaluations differ by up to twice that.
    const int k = 2 * (27 + 45 + 24) + 3 * 3 + 2 * 3 + 10;
    const auto vs_fused = ngi::test::check_close(
        got, want, Tol::sum_of(2 * k, mag, "two float32 evaluations of one network, each within gamma_k S"));
    const auto vs_ref = ngi::test::check_close(got, r, Tol::sum_of(k, mag, "a float32 evaluation vs the double one"));
    const auto fused_vs_ref = ngi::test::check_close(want, r, Tol::sum_of(k, mag, "as above"));
    WARN("chain: max |unfused at load - fused file| = " << vs_fused.max_abs << " (max |y| " << vs_fused.scale
         << "); vs the double reference: unfused " << vs_ref.max_abs << ", fused file " << fused_vs_ref.max_abs);
}

TEST_CASE("graph fusion at load: dense, batch norm, tanh, dense on items as the fused file", "[model][graph][fuse]") {
    std::mt19937 rng(4902);
    const int C0 = 6, C1 = 5, C2 = 3, N = 7;
    FuseTensors t = {{"d1.w", {{C1, C0}, ngi::test::random_vector(C1 * C0, rng)}},
                     {"d1.b", {{C1}, ngi::test::random_vector(C1, rng)}},
                     {"d2.w", {{C2, C1}, ngi::test::random_vector(C2 * C1, rng)}}};
    const FuseBatchNorm bn = random_batch_norm(C1, rng);
    FuseTensors unfused = t;
    unfused["bn.s"] = {{C1}, to_float(bn.scale)};
    unfused["bn.t"] = {{C1}, to_float(bn.shift)};
    const json d1 = {{"name", "d1"}, {"op", "dense"}, {"inputs", {"x"}}, {"output", "h"}, {"in", C0}, {"out", C1},
                     {"weight", "d1.w"}, {"bias", "d1.b"}};
    const json d2 = {{"name", "d2"}, {"op", "dense"}, {"inputs", {"a"}}, {"output", "y"}, {"in", C1}, {"out", C2},
                     {"weight", "d2.w"}};
    const json unfused_cfg = fuse_config(
        C0, "y",
        {d1,
         {{"name", "bn"}, {"op", "affine"}, {"inputs", {"h"}}, {"output", "n"}, {"scale", "bn.s"}, {"shift", "bn.t"}},
         {{"name", "th"}, {"op", "activation"}, {"inputs", {"n"}}, {"output", "a"}, {"activation", "tanh"}}, d2},
        "nc");
    FuseTensors fused = t;
    converter_fold(fused["d1.w"], fused["d1.b"], bn.scale, bn.shift, C0, C1);
    json f1 = d1;
    f1["output"] = "a";
    f1["activation"] = "tanh";
    const json fused_cfg = fuse_config(C0, "y", {f1, d2}, "nc");

    const FuseSummary s = fuse_summary(unfused_cfg, unfused);
    CHECK((s.affines == 1 && s.activations == 1 && s.input_activations == 0));
    CHECK(s.labels == std::vector<std::string>{"d1 + bn + th", "d2"});
    ngi::Tensor x({N, C0});
    x.data = ngi::test::random_vector(x.data.size(), rng);
    const std::vector<float> got = run_fuse_file(write_fuse_file("dense_unfused", unfused, unfused_cfg), x);
    const std::vector<float> want = run_fuse_file(write_fuse_file("dense_fused", fused, fused_cfg), x);
    std::vector<double> mag;
    for (int i = 0; i < N; ++i) {  // magnitudes: the chain on absolute values
        std::vector<double> v(x.data.begin() + i * C0, x.data.begin() + (i + 1) * C0);
        for (double& e : v) e = std::abs(e);
        std::vector<float> b(C1);
        for (int c = 0; c < C1; ++c)
            b[c] = std::abs(t["d1.b"].data[c]) * float(std::abs(bn.scale[c])) + float(std::abs(bn.shift[c]));
        std::vector<float> ws = abs_of(t["d1.w"].data);
        for (int o = 0; o < C1; ++o)
            for (int k = 0; k < C0; ++k) ws[o * C0 + k] *= float(std::abs(bn.scale[o]));
        const std::vector<double> y =
            ngi::ref::dense(ngi::ref::dense(v, ws, b, C1, 0, 0), abs_of(t["d2.w"].data), {}, C2, 0, 0);
        mag.insert(mag.end(), y.begin(), y.end());
    }
    // 6 + 5 terms, bias, scale, shift, the folded weights' roundings, tanh (10 u of S); twice that between two.
    const int k = 2 * (2 * (6 + 5) + 3 + 2 * 2 + 10);
    const auto r = ngi::test::check_close(got, want, Tol::sum_of(k, mag, "two float32 evaluations of one network"));
    WARN("dense: max |unfused at load - fused file| = " << r.max_abs << " (max |y| " << r.scale << ")");
}

TEST_CASE("graph fusion at load: a leaky relu read by two convolutions becomes their input activation",
          "[model][graph][fuse]") {
    std::mt19937 rng(4903);
    const FuseTensors t = {{"a.w", {{3, 2, 3, 3}, ngi::test::random_vector(54, rng)}},
                           {"a.b", {{3}, ngi::test::random_vector(3, rng)}},
                           {"b.w", {{2, 2, 1, 1}, ngi::test::random_vector(4, rng)}}};
    const json a = {{"name", "a"}, {"op", "conv2d"}, {"inputs", {"r"}}, {"output", "ya"}, {"in", 2}, {"out", 3},
                    {"kernel", {3, 3}}, {"stride", 1}, {"pad", 1}, {"weight", "a.w"}, {"bias", "a.b"}};
    const json b = {{"name", "b"}, {"op", "conv2d"}, {"inputs", {"r"}}, {"output", "yb"}, {"in", 2}, {"out", 2},
                    {"kernel", {1, 1}}, {"stride", 1}, {"pad", 0}, {"weight", "b.w"}, {"activation", "sigmoid"}};
    const json cat = {{"name", "cat"}, {"op", "concat"}, {"inputs", {"ya", "yb"}}, {"output", "y"}};
    const json unfused_cfg = fuse_config(
        2, "y",
        {{{"name", "r"}, {"op", "activation"}, {"inputs", {"x"}}, {"output", "r"}, {"activation", "leaky_relu"},
          {"slope", 0.2}},
         a, b, cat});
    json fa = a, fb = b;
    for (json* f : {&fa, &fb}) {
        (*f)["inputs"] = {"x"};
        (*f)["input_activation"] = "leaky_relu";
        (*f)["slope"] = 0.2;
    }
    const json fused_cfg = fuse_config(2, "y", {fa, fb, cat});
    const FuseSummary s = fuse_summary(unfused_cfg, t);
    CHECK((s.affines == 0 && s.activations == 0 && s.input_activations == 1));
    CHECK(s.labels == std::vector<std::string>{"a + r", "b + r", "cat"});
    const FuseSummary again = fuse_summary(fused_cfg, t);
    CHECK(again.affines + again.activations + again.input_activations == 0);
    ngi::Tensor x({1, 2, 6, 7});
    x.data = ngi::test::random_vector(x.data.size(), rng);
    // No weight changes: the same ops as the fused file's, bit for bit.
    ngi::test::check_close(run_fuse_file(write_fuse_file("shared_unfused", t, unfused_cfg), x),
                           run_fuse_file(write_fuse_file("shared_fused", t, fused_cfg), x), Tol::bits());
}

TEST_CASE("graph fusion at load: what must not fold stays a node", "[model][graph][fuse]") {
    std::mt19937 rng(4904);
    auto conv = [](const std::string& name, const std::string& in, const std::string& out, const std::string& w) {
        return json{{"name", name}, {"op", "conv2d"}, {"inputs", {in}}, {"output", out}, {"in", 2}, {"out", 2},
                    {"kernel", {3, 3}}, {"stride", 1}, {"pad", 1}, {"weight", w}};
    };
    auto act = [](const std::string& name, const std::string& in, const std::string& out, const std::string& a) {
        return json{{"name", name}, {"op", "activation"}, {"inputs", {in}}, {"output", out}, {"activation", a}};
    };
    FuseTensors t;
    for (const char* w : {"c.w", "e.w", "f.w", "g.w", "h.w"}) t[w] = {{2, 2, 3, 3}, ngi::test::random_vector(36, rng)};
    t["a.s"] = {{2}, {1.5f, -0.75f}};
    t["a.t"] = {{2}, {0.25f, 0.5f}};
    const std::vector<float> one = {1, 1}, zero = {0, 0};
    const int H = 5, W = 6;
    ngi::Tensor x({1, 2, H, W});
    x.data = ngi::test::random_vector(x.data.size(), rng);
    int oh = 0, ow = 0;
    auto ref = [&](const std::vector<float>& in, const char* w, int in_act, int out_act, double slope) {
        return ngi::ref::conv2d(in, 2, H, W, t[w].data, 2, 3, 3, 1, 1, one, zero, in_act, out_act, slope, oh, ow);
    };
    const Tol tol = Tol::relative(1e-5, "18- and 36-term float32 sums of terms below 1 with activations")
                        .or_absolute(1e-5);

    SECTION("a producer with two readers, an activation read by a convolution and a concat") {
        // c's output is read by the affine and by conv e: neither the affine nor (after it) the relu folds into c; the
        // relu is read by conv f and by the concat, so it stays a node too.
        json nodes = {conv("c", "x", "tc", "c.w"),
                      {{"name", "a"}, {"op", "affine"}, {"inputs", {"tc"}}, {"output", "ta"}, {"scale", "a.s"},
                       {"shift", "a.t"}},
                      conv("e", "tc", "te", "e.w"), act("r", "ta", "tr", "relu"), conv("f", "tr", "tf", "f.w"),
                      {{"name", "cat"}, {"op", "concat"}, {"inputs", {"tr", "te", "tf"}}, {"output", "y"}}};
        const json cfg = fuse_config(2, "y", nodes);
        t.erase("g.w");
        t.erase("h.w");
        const FuseSummary s = fuse_summary(cfg, t);
        CHECK((s.affines == 0 && s.activations == 0 && s.input_activations == 0 && s.labels.size() == 6));
        const std::vector<float> c = ref(x.data, "c.w", 0, 0, 0);
        std::vector<float> r(c.size());
        for (std::size_t i = 0; i < c.size(); ++i)
            r[i] = std::max(0.0f, float(double(c[i]) * t["a.s"].data[i / (H * W)] + t["a.t"].data[i / (H * W)]));
        std::vector<float> want = r;
        for (const std::vector<float>& part : {ref(c, "e.w", 0, 0, 0), ref(r, "f.w", 0, 0, 0)})
            want.insert(want.end(), part.begin(), part.end());
        ngi::test::check_close(run_fuse_file(write_fuse_file("two_readers", t, cfg), x), want, tol);
    }
    SECTION("the graph output counts as a reader") {
        // y is conv c's output and the graph output: the affine reading it does not fold (the output would change);
        // the relu r is the output of a second graph: it does not fold into the convolution reading it.
        const json cfg = fuse_config(2, "y", {conv("c", "x", "y", "c.w"),
                                              {{"name", "a"}, {"op", "affine"}, {"inputs", {"y"}}, {"output", "z"},
                                               {"scale", "a.s"}}});
        FuseTensors ts = t;
        ts.erase("a.t");
        for (const char* w : {"e.w", "f.w", "g.w", "h.w"}) ts.erase(w);
        const FuseSummary s = fuse_summary(cfg, ts);
        CHECK((s.affines == 0 && s.labels.size() == 2));
        ngi::test::check_close(run_fuse_file(write_fuse_file("output_affine", ts, cfg), x), ref(x.data, "c.w", 0, 0, 0),
                               tol);
        const json cfg2 = fuse_config(2, "y", {act("r", "x", "y", "relu"), conv("e", "y", "z", "e.w")});
        FuseTensors te = {{"e.w", t["e.w"]}};
        const FuseSummary s2 = fuse_summary(cfg2, te);
        CHECK((s2.input_activations == 0 && s2.labels.size() == 2));
        std::vector<float> relu = x.data;
        for (float& v : relu) v = std::max(v, 0.0f);
        ngi::test::check_close(run_fuse_file(write_fuse_file("output_relu", te, cfg2), x), relu, Tol::exact());
    }
    SECTION("no slope changes meaning") {
        // One `slope` serves a node's input_activation and activation. (1) c has a leaky input activation of slope
        // 0.1 (a file the converter fused): a leaky ReLU of 0.3 after it stays a node, one of 0.1 folds. (2) g has a
        // leaky output activation of the default slope 0.01: a leaky ReLU of 0.2 before it stays a node; a ReLU
        // (whose stray slope field means nothing) before h folds without touching h's slope.
        json c = conv("c", "x", "tc", "c.w"), e = conv("e", "x", "te", "e.w"), g = conv("g", "l3", "tg", "g.w"),
             h = conv("h", "r4", "th", "h.w");
        for (json* n : {&c, &e}) {
            (*n)["input_activation"] = "leaky_relu";
            (*n)["slope"] = 0.1;
        }
        g["activation"] = "leaky_relu";
        h["activation"] = "leaky_relu";
        json l1 = act("l1", "tc", "t1", "leaky_relu"), l2 = act("l2", "te", "t2", "leaky_relu"),
             l3 = act("l3", "x", "l3", "leaky_relu"), r4 = act("r4", "x", "r4", "relu");
        l1["slope"] = 0.3;
        l2["slope"] = 0.1;
        l3["slope"] = 0.2;
        r4["slope"] = 0.5;
        const json cfg = fuse_config(2, "y", {c, l1, e, l2, l3, g, r4, h,
                                              {{"name", "cat"}, {"op", "concat"}, {"inputs", {"t1", "t2", "tg", "th"}},
                                               {"output", "y"}}});
        FuseTensors ts = t;
        ts.erase("a.s");
        ts.erase("a.t");
        ts.erase("f.w");
        const FuseSummary s = fuse_summary(cfg, ts);
        CHECK((s.affines == 0 && s.activations == 1 && s.input_activations == 1));
        CHECK(s.labels == std::vector<std::string>{"c", "l1", "e + l2", "l3", "g", "h + r4", "cat"});
        std::vector<float> want, t1 = ref(x.data, "c.w", 2, 0, 0.1);
        for (float& v : t1) v = v >= 0 ? v : float(0.3 * v);
        std::vector<float> l3v = x.data;
        for (float& v : l3v) v = v >= 0 ? v : float(0.2 * v);
        for (const std::vector<float>& part : {t1, ref(x.data, "e.w", 2, 2, 0.1), ref(l3v, "g.w", 0, 2, 0.01),
                                               ref(x.data, "h.w", 1, 2, 0.01)})
            want.insert(want.end(), part.begin(), part.end());
        ngi::test::check_close(run_fuse_file(write_fuse_file("slopes", ts, cfg), x), want, tol);
    }
    SECTION("a fold that would overflow float32 is not made") {
        // 1e5 x 1e34 is beyond float32: the network as written computes x * 1e5 first, then scales it.
        FuseTensors ts = {{"c.w", {{2, 2, 1, 1}, {1e5f, 0, 0, 1e5f}}}, {"a.s", {{2}, {1e34f, 1e34f}}}};
        const json cfg = fuse_config(2, "y", {{{"name", "c"}, {"op", "conv2d"}, {"inputs", {"x"}}, {"output", "tc"},
                                               {"in", 2}, {"out", 2}, {"kernel", {1, 1}}, {"stride", 1}, {"pad", 0},
                                               {"weight", "c.w"}},
                                              {{"name", "a"}, {"op", "affine"}, {"inputs", {"tc"}}, {"output", "y"},
                                               {"scale", "a.s"}}});
        CHECK(fuse_summary(cfg, ts).affines == 0);
        ngi::Tensor tiny({1, 2, 1, 1});
        tiny.data = {1e-30f, -2e-30f};
        const std::vector<float> y = run_fuse_file(write_fuse_file("overflow", ts, cfg), tiny);
        ngi::test::check_close(y, std::vector<double>{1e9, -2e9}, Tol::relative(1e-6, "two float32 products"));
    }
}
