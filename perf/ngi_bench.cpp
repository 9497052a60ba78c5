// ngi_bench: kernel and model microbenchmarks. Prints one JSON object on stdout, progress on stderr.
//
//   ngi_bench gemm [--device D] [--repeats R]          GEMM GFLOP/s at 1024^3 and at the thesis generator's
//                                                       layer shapes (conv: M=Cout, N=HWout, K=Cin*16;
//                                                       transposed conv: M=Cout*16, N=HWin, K=Cin)
//   ngi_bench tune [--device D] [--max N | --sets "A;B;..."] [--shapes "M,N,K;..."] [--repeats R]
//                  [--write-db kernels/gemm_tuning.json]
//                                                       try GEMM parameter sets (each checked against a
//                                                       reference first; failing to build or launch = rejected,
//                                                       CLBlast style) and rank them by the geomean GFLOP/s over
//                                                       the shapes (default 1024^3, down1, up2); --max: the first N
//                                                       of the space only; --sets: these knob sets only (each
//                                                       still checked first); --shapes: other GEMM shapes (slow
//                                                       devices such as llvmpipe, where one 1024^3 run takes
//                                                       minutes); each row also has check_ms, the wall time of the
//                                                       self-check including the program build (cold with an
//                                                       empty NGI_CACHE_DIR); --write-db: add or replace this
//                                                       device's entry in the tuning database (platform + vendor
//                                                       + device + driver) with the winner
//   ngi_bench mlp --model M.safetensors [--width 1920 --height 1080] [--path fused|dense] [--ao] [--repeats R]
//                                                       a per-pixel MLP over W x H pixels, device in, device out
//                                                       (Model::enqueue): median ms and GFLOP/s (2 x MACs); --ao:
//                                                       the whole AO network (ring gather + MLP + clamp)
//   ngi_bench conv [--device D] [--repeats R] [--width 1024 --height 512] [--only up1,down3] [--path implicit]
//                                                       the thesis generator's 16 convolution layers, each through
//                                                       both paths (im2col / col2im and the implicit GEMM), device
//                                                       time per kernel (median of R profiled runs): before/after
//                                                       per layer
//   ngi_bench generator --model M.safetensors [--width 1024 --height 512] [--repeats R] [--device D]
//                       [--bn-mode running|per_image]
//                                                       whole-model wall time (median) + per-op device time
//   ngi_bench neural-gi --model M.safetensors [--frames 128:1,256:4,...] [--repeats R] [--device D] [--no-profile]
//                                                       seed 002 on a synthetic frame (a room filling the model's
//                                                       scene box, one block in it, a ceiling area light), per face
//                                                       size N and upsampling K ("N:K"; default 128:1, 128:2,
//                                                       128:4, 256:1, 256:2, 256:4, 512:4, 1024:4):
//                                                       NeuralGiRenderer::run (wall time: four face planes up,
//                                                       input assembly, the network at N/K, joint bilateral
//                                                       upsampling to N, lighting, two downloads), and its parts
//                                                       alone: the network at N/K (Model::enqueue, device in and
//                                                       out), the upsampling kernel (N/K -> N); unless
//                                                       --no-profile, the network's device time per op kind from
//                                                       one profiled run. Pairs the model cannot run (N/K not a
//                                                       multiple of 2^num_downs) are listed as skipped, with why
//
// Timings: warm-up first (PoCL compiles work-group functions at the first launch), then the median of R runs.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "ngi/ao.hpp"
#include "ngi/model.hpp"
#include "ngi/neural_gi.hpp"
#include "ops/conv.hpp"
#include "ops/gemm.hpp"
#include "ops/gemm_selfcheck.hpp"
#include "ops/gemm_tuning.hpp"
#include "ops/jbu.hpp"

using namespace ngi;
using namespace ngi::detail;
using json = nlohmann::json;

namespace {

std::string arg(int argc, char** argv, const char* name, const std::string& fallback = "") {
    for (int i = 2; i + 1 < argc; ++i)
        if (!std::strcmp(argv[i], name)) return argv[i + 1];
    return fallback;
}

std::vector<std::string> split(const std::string& s, char separator = ',') {
    std::vector<std::string> out;
    std::size_t start = 0;
    while (start < s.size()) {
        const std::size_t end = std::min(s.find(separator, start), s.size());
        if (end > start) out.push_back(s.substr(start, end - start));
        start = end + 1;
    }
    return out;
}

bool has_flag(int argc, char** argv, const char* name) {
    return std::find_if(argv + 2, argv + argc, [&](const char* a) { return !std::strcmp(a, name); }) != argv + argc;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

template <class F>
std::vector<double> time_runs(Context& ctx, int repeats, F&& f) {
    f();  // warm-up
    ctx.finish();
    std::vector<double> ms;
    for (int r = 0; r < repeats; ++r) {
        auto t0 = std::chrono::steady_clock::now();
        f();
        ctx.finish();
        ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    return ms;
}

struct GemmShape {
    std::string name;
    int m, n, k;
};

// The thesis generator (12 -> 3 channels, ngf 64, 8 downs) at 1024 x 512, as GEMMs.
std::vector<GemmShape> generator_shapes() {
    std::vector<GemmShape> s;
    int c = 12, h = 512, w = 1024;
    const int inner[8] = {64, 128, 256, 512, 512, 512, 512, 512};
    for (int i = 0; i < 8; ++i) {
        h /= 2, w /= 2;
        s.push_back({"down" + std::to_string(i), inner[i], h * w, c * 16});
        c = inner[i];
    }
    for (int i = 7; i >= 0; --i) {  // up-conv input is h x w (then doubled), cin = 2*inner except innermost
        const int cin = i == 7 ? inner[i] : 2 * inner[i], cout = i == 0 ? 3 : inner[i - 1];
        s.push_back({"up" + std::to_string(i), cout * 16, h * w, cin});
        h *= 2, w *= 2;
    }
    return s;
}

struct GemmBuffers {
    Buffer a, b, c, scale, shift;
};

GemmBuffers make_gemm_buffers(Context& ctx, const GemmParams& p, int M, int N, int K, std::mt19937& rng,
                              std::vector<float>* a_out = nullptr, std::vector<float>* b_out = nullptr) {
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<float> a(std::size_t(M) * K), b(std::size_t(K) * N);
    for (auto& x : a) x = u(rng);
    for (auto& x : b) x = u(rng);
    // Pack B on the host the way im2col would (panels of NR columns, zero padded).
    const int nr = p.nr(), kp = padded_k(K, p);
    std::vector<float> bp(packed_b_floats(K, N, p), 0.0f);
    for (int k = 0; k < K; ++k)
        for (int n = 0; n < N; ++n) bp[(std::size_t(n / nr) * kp + k) * nr + n % nr] = b[std::size_t(k) * N + n];
    const auto ap = pack_a(a.data(), M, K, K, p);
    GemmBuffers g;
    g.a = ctx.alloc(ap.size() * 4, "bench A");
    ctx.write(g.a, 0, ap.size() * 4, ap.data(), "bench A");
    g.b = ctx.alloc(bp.size() * 4, "bench B");
    ctx.write(g.b, 0, bp.size() * 4, bp.data(), "bench B");
    g.c = ctx.alloc(std::size_t(M) * N * 4, "bench C");
    std::vector<float> one(M, 1.0f), zero(M, 0.0f);
    g.scale = ctx.alloc(M * 4, "bench scale");
    ctx.write(g.scale, 0, M * 4, one.data(), "bench scale");
    g.shift = ctx.alloc(M * 4, "bench shift");
    ctx.write(g.shift, 0, M * 4, zero.data(), "bench shift");
    if (a_out) *a_out = std::move(a);
    if (b_out) *b_out = std::move(b);
    return g;
}

// "M,N,K;M,N,K" -> shapes named "MxNxK" (ngi_bench tune --shapes).
std::vector<GemmShape> parse_gemm_shapes(const std::string& list) {
    std::vector<GemmShape> shapes;
    for (const std::string& item : split(list, ';')) {
        GemmShape s{"", 0, 0, 0};
        char tail = 0;
        if (std::sscanf(item.c_str(), "%d,%d,%d%c", &s.m, &s.n, &s.k, &tail) != 3 || s.m < 1 || s.n < 1 || s.k < 1)
            throw InputError("tune: --shapes takes \"M,N,K;M,N,K\" with positive sizes, got '" + item + "'");
        s.name = std::to_string(s.m) + "x" + std::to_string(s.n) + "x" + std::to_string(s.k);
        shapes.push_back(s);
    }
    if (shapes.empty()) throw InputError("tune: --shapes names no shape");
    return shapes;
}

json bench_gemm(Context& ctx, const GemmParams& p, const GemmShape& s, int repeats) {
    std::mt19937 rng(1);
    Gemm gemm(ctx, p);
    GemmBuffers g = make_gemm_buffers(ctx, p, s.m, s.n, s.k, rng);
    const auto ms = time_runs(ctx, repeats, [&] {
        gemm.enqueue(ctx, s.m, s.n, s.k, g.a.get(), g.b.get(), 0, g.c.get(), 0, s.n, g.scale.get(), g.shift.get(),
                     Act::none());
    });
    const double med = median(ms);
    return {{"name", s.name}, {"M", s.m}, {"N", s.n}, {"K", s.k}, {"ms", med},
            {"gflops", 2.0 * s.m * s.n * s.k / (med * 1e-3) / 1e9}};
}

json device_json(const Device& d, const GemmParams& p) {
    const auto& i = d.info();
    return {{"name", i.name}, {"platform", i.platform_name}, {"driver", i.driver_version},
            {"compute_units", i.compute_units}, {"gemm_params", p.to_string()}};
}

int run_gemm(int argc, char** argv) {
    Device d = Device::open(arg(argc, argv, "--device"));
    const int repeats = std::stoi(arg(argc, argv, "--repeats", "7"));
    // The variant the self-check accepted (what models run), not the table's choice: a variant that fails the check
    // is never timed. Throws, naming every rejection, where no variant computes correct results.
    const ngi::detail::GemmSelection& selected = ngi::detail::gemm_selection(ngi::detail::context_of(d));
    const GemmParams p = selected.params;
    json rejected = json::array();
    for (const auto& [params, verdict] : selected.rejected) rejected.push_back(params.to_string() + ": " + verdict.reason);
    json out = {{"device", device_json(d, p)}, {"repeats", repeats}, {"rejected", rejected}};
    std::fprintf(stderr, "gemm 1024^3 ...\n");
    out["gemm_1024"] = bench_gemm(ngi::detail::context_of(d), p, {"1024^3", 1024, 1024, 1024}, repeats);
    json layers = json::array();
    double flop = 0, ms = 0;
    for (const auto& s : generator_shapes()) {
        std::fprintf(stderr, "gemm %s (M %d N %d K %d) ...\n", s.name.c_str(), s.m, s.n, s.k);
        layers.push_back(bench_gemm(ngi::detail::context_of(d), p, s, std::max(1, repeats / 2)));
        flop += 2.0 * s.m * s.n * s.k;
        ms += layers.back()["ms"].get<double>();
    }
    out["generator_layers"] = layers;
    out["generator_gemm_total"] = {{"gflop", flop / 1e9}, {"ms", ms}, {"gflops", flop / (ms * 1e-3) / 1e9}};
    std::printf("%s\n", out.dump(2).c_str());
    return 0;
}

// One layer of the thesis generator as a convolution (ngi_bench conv).
struct ConvLayer {
    std::string name;
    bool transposed;
    int cin, cout, h, w;  // input
    Activation in_act, out_act;
};

std::vector<ConvLayer> generator_conv_layers(int width, int height) {
    std::vector<ConvLayer> s;
    int c = 12, h = height, w = width;
    const int inner[8] = {64, 128, 256, 512, 512, 512, 512, 512};
    for (int i = 0; i < 8; ++i) {  // pix2pix: LeakyReLU before every down-conv but the first
        s.push_back({"down" + std::to_string(i), false, c, inner[i], h, w,
                     i == 0 ? Activation::None : Activation::LeakyReLU, Activation::None});
        c = inner[i], h /= 2, w /= 2;
    }
    for (int i = 7; i >= 0; --i) {  // ReLU before every up-conv; tanh after the outermost
        const int cin = i == 7 ? inner[i] : 2 * inner[i], cout = i == 0 ? 3 : inner[i - 1];
        s.push_back({"up" + std::to_string(i), true, cin, cout, h, w, Activation::ReLU,
                     i == 0 ? Activation::Tanh : Activation::None});
        h *= 2, w *= 2;
    }
    return s;
}

int run_conv(int argc, char** argv) {
    Device d = Device::open(arg(argc, argv, "--device"), DeviceOptions{true});
    Context& ctx = ngi::detail::context_of(d);
    const int repeats = std::stoi(arg(argc, argv, "--repeats", "5"));
    const int width = std::stoi(arg(argc, argv, "--width", "1024")), height = std::stoi(arg(argc, argv, "--height", "512"));
    const GemmParams p = gemm_params_for(d.info());
    // The implicit path's set ($NGI_CONV_GEMM, the database); the GEMM's where the database turns the path off.
    const GemmParams conv_p = conv_params_for(d.info(), p).value_or(p);
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(-0.05f, 0.05f);
    json layers = json::array();
    double total[2] = {0, 0};
    // e.g. --only up1,down3; built by append: GCC 12's -Wrestrict misfires on `"literal" + std::string&&`
    const std::string only = std::string(",").append(arg(argc, argv, "--only")).append(",");
    for (const auto& l : generator_conv_layers(width, height)) {
        if (only != ",," && only.find("," + l.name + ",") == std::string::npos) continue;
        const ConvSpec spec{l.cin, l.cout, {4, 4, 2, 1}, {l.in_act, 0.2f}, {l.out_act, 0.2f}};
        std::vector<float> weight(std::size_t(l.cin) * l.cout * 16), x(std::size_t(l.cin) * l.h * l.w);
        for (auto& v : weight) v = u(rng);
        for (auto& v : x) v = 20 * u(rng);
        const Shape in{l.cin, l.h, l.w};
        Buffer xb = ctx.alloc(x.size() * 4, "bench x");
        ctx.write(xb, 0, x.size() * 4, x.data(), "bench x");
        json row = {{"name", l.name}, {"cin", l.cin}, {"cout", l.cout}, {"in_h", l.h}, {"in_w", l.w}};
        double gflop = 0;
        int path_index = 0;
        for (ConvPath path : {ConvPath::im2col, ConvPath::implicit}) {
            const std::string want = arg(argc, argv, "--path");  // im2col | implicit: that path only
            if (!want.empty() && want != (path == ConvPath::im2col ? "im2col" : "implicit")) {
                ++path_index;
                continue;
            }
            const char* path_name = path == ConvPath::im2col ? "im2col" : "implicit";
            auto measure = [&](auto& op) {
                const Shape out = op.output_shape(in);
                gflop = 2.0 * l.cin * l.cout * 16 * (l.transposed ? double(in.h) * in.w : double(out.h) * out.w) / 1e9;
                Buffer yb = ctx.alloc(out.size() * 4, "bench y");
                Buffer sb = ctx.alloc(std::max<std::size_t>(1, op.scratch_floats(in)) * 4, "bench scratch");
                std::vector<std::vector<double>> kernel_ms;  // [kernel position][run]
                std::vector<double> totals;
                for (int r = -1; r < repeats; ++r) {  // r = -1: warm-up
                    std::vector<cl_event> ev;
                    op.enqueue(ctx, View{xb.get(), 0, in}, View{yb.get(), 0, out}, sb.get(), 0, &ev);
                    ctx.finish();
                    double sum = 0;
                    for (std::size_t k = 0; k < ev.size(); ++k) {
                        cl_ulong t0 = 0, t1 = 0;
                        clGetEventProfilingInfo(ev[k], CL_PROFILING_COMMAND_START, sizeof t0, &t0, nullptr);
                        clGetEventProfilingInfo(ev[k], CL_PROFILING_COMMAND_END, sizeof t1, &t1, nullptr);
                        clReleaseEvent(ev[k]);
                        if (r < 0) continue;
                        if (kernel_ms.size() <= k) kernel_ms.resize(k + 1);
                        kernel_ms[k].push_back((t1 - t0) * 1e-6);
                        sum += (t1 - t0) * 1e-6;
                    }
                    if (r >= 0) totals.push_back(sum);
                }
                json kernels = json::array();
                for (auto& k : kernel_ms) kernels.push_back(median(k));
                const double med = median(totals);
                total[path_index] += med;
                row[path_name] = {{"ms", med}, {"gflops", gflop / (med * 1e-3)}, {"kernels_ms", kernels},
                                  {"scratch_mib", op.scratch_floats(in) * 4.0 / 1048576.0},
                                  {"implicit", op.implicit()}};
            };
            if (l.transposed) {
                ConvTranspose2d op(ctx, p, spec, weight.data(), {}, path, conv_p);
                measure(op);
            } else {
                Conv2d op(ctx, p, spec, weight.data(), {}, path, conv_p);
                measure(op);
            }
            ++path_index;
        }
        row["gflop"] = gflop;
        for (const char* path_name : {"im2col", "implicit"})
            if (row.contains(path_name))
                std::fprintf(stderr, "%-6s %-8s %8.2f ms\n", l.name.c_str(), path_name, row[path_name]["ms"].get<double>());
        layers.push_back(row);
    }
    json out = {{"device", device_json(d, p)}, {"conv_params", conv_p.to_string()}, {"repeats", repeats},
                {"width", width}, {"height", height},
                {"layers", layers}, {"total_ms", {{"im2col", total[0]}, {"implicit", total[1]}}}};
    std::printf("%s\n", out.dump(2).c_str());
    return 0;
}

int run_tune(int argc, char** argv) {
    Device d = Device::open(arg(argc, argv, "--device"));
    // Every candidate passes the library's own self-check (small and realistic problems against a host
    // reference) before it is timed: a variant the device computes wrongly never reaches the table.
    std::vector<GemmParams> space = gemm_tuning_space(d.info());
    if (const int max = std::stoi(arg(argc, argv, "--max", "0")); max > 0 && std::size_t(max) < space.size())
        space.resize(std::size_t(max));  // the database's current choice stays first
    if (const std::string sets = arg(argc, argv, "--sets"); !sets.empty()) {  // "a;b;c": exactly these candidates
        space.clear();
        for (const std::string& item : split(sets, ';')) space.push_back(parse_gemm_params(item));
    }
    std::vector<GemmShape> shapes = {{"1024^3", 1024, 1024, 1024}, {"down1", 128, 32768, 1024}, {"up2", 2048, 2048, 1024}};
    if (const std::string list = arg(argc, argv, "--shapes"); !list.empty()) shapes = parse_gemm_shapes(list);
    const int repeats = std::stoi(arg(argc, argv, "--repeats", "3"));
    if (repeats < 1) throw InputError("tune: --repeats must be at least 1");
    std::string shape_names;
    for (const auto& s : shapes) shape_names += (shape_names.empty() ? "" : ", ") + s.name;
    json results = json::array();
    for (const auto& p : space) {
        json r = {{"params", p.to_string()}};
        const auto check_start = std::chrono::steady_clock::now();
        const GemmVerdict v = check_gemm_variant(ngi::detail::context_of(d), p, gemm_check_problems());
        r["check_ms"] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - check_start).count();
        if (!v.ok) {
            r["rejected"] = v.reason;
        } else {
            double sum = 0;
            for (const auto& s : shapes) {
                r[s.name] = bench_gemm(ngi::detail::context_of(d), p, s, repeats)["gflops"];
                sum += std::log(r[s.name].get<double>());
            }
            r["geomean_gflops"] = std::exp(sum / double(shapes.size()));
        }
        std::fprintf(stderr, "%s\n", r.dump().c_str());
        results.push_back(r);
    }
    std::sort(results.begin(), results.end(), [](const json& a, const json& b) {
        return a.value("geomean_gflops", 0.0) > b.value("geomean_gflops", 0.0);
    });
    std::printf("%s\n", json{{"device", device_json(d, gemm_params_for(d.info()))}, {"shapes", shape_names},
                             {"repeats", repeats}, {"ranked", results}}.dump(2).c_str());
    if (const std::string db_path = arg(argc, argv, "--write-db"); !db_path.empty()) {
        if (results.empty() || !results[0].contains("geomean_gflops"))
            throw Error("tune: no candidate passed the check on " + d.info().name + "; " + db_path + " left unchanged");
        const DeviceInfo& i = d.info();
        GemmTuningEntry e;
        e.platform = i.platform_name;
        e.vendor = i.vendor;
        e.device = i.name;
        e.driver = i.driver_version;
        e.params = parse_gemm_params(results[0]["params"].get<std::string>());
        double current = 0;  // the entry the database gave this device before, measured in the same run
        for (const auto& r : results)
            if (r["params"] == space.front().to_string()) current = r.value("geomean_gflops", 0.0);
        char note[512];
        std::snprintf(note, sizeof note, "ngi_bench tune: geomean %.3g GFLOP/s over %s (the previous "
                      "choice %s: %.3g), %zu candidates checked", results[0]["geomean_gflops"].get<double>(),
                      shape_names.c_str(), space.front().to_string().c_str(), current, space.size());
        e.note = note;
        std::ifstream in(db_path);
        if (!in) throw InputError("tune: cannot read " + db_path);
        const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        const std::string tmp = db_path + ".tmp";
        {
            std::ofstream out(tmp);
            out << gemm_tuning_with(text, e);
            if (!out.flush()) throw InputError("tune: cannot write " + tmp);
        }
        std::filesystem::rename(tmp, db_path);
        std::fprintf(stderr, "tune: %s -> %s in %s (rebuild to compile it in)\n", i.name.c_str(),
                     e.params.to_string().c_str(), db_path.c_str());
    }
    return 0;
}

int run_generator(int argc, char** argv) {
    const std::string path = arg(argc, argv, "--model");
    if (path.empty()) throw InputError("generator: --model M.safetensors is required");
    const int w = std::stoi(arg(argc, argv, "--width", "1024")), h = std::stoi(arg(argc, argv, "--height", "512"));
    const int repeats = std::stoi(arg(argc, argv, "--repeats", "5"));
    const std::string device_spec = arg(argc, argv, "--device");

    json out;
    {
        Device d = Device::open(device_spec);
        ModelOptions options;
        options.bn_mode = arg(argc, argv, "--bn-mode");  // "" = the file's; the loader checks the value
        Model m = Model::load(d, path, options);
        const auto& c = m.config();
        Tensor x({1, c.input_nc, h, w});
        std::mt19937 rng(3);
        std::uniform_real_distribution<float> u(-1, 1);
        for (auto& v : x.data) v = u(rng);
        if (const std::string in = arg(argc, argv, "--input"); !in.empty()) x = read_npy(in);
        std::fprintf(stderr, "generator %s %dx%d: warm-up + %d runs ...\n", c.family.c_str(), w, h, repeats);
        RunInfo info;
        Tensor y;
        const auto ms = time_runs(ngi::detail::context_of(d), repeats, [&] { y = m.run(x, &info); });
        if (const std::string o = arg(argc, argv, "--output"); !o.empty()) write_npy(o, y);
        out = {{"device", device_json(d, gemm_params_for(d.info()))},
               {"model", {{"family", c.family}, {"ngf", c.unet.ngf}, {"num_downs", c.unet.num_downs},
                          {"bn_mode", c.unet.bn_mode}, {"width", w}, {"height", h}}},
               {"ms_median", median(ms)}, {"ms_all", ms},
               {"memory_mib", {{"weights", info.weight_bytes / 1048576.0}, {"arena", info.arena_bytes / 1048576.0},
                               {"arena_without_reuse", info.naive_bytes / 1048576.0},
                               {"scratch", info.scratch_bytes / 1048576.0}}}};
    }
    {  // One profiled run for the per-op breakdown (profiling can perturb the total, so it is timed apart).
        Device d = Device::open(device_spec, DeviceOptions{true});
        ModelOptions options;
        options.bn_mode = arg(argc, argv, "--bn-mode");
        Model m = Model::load(d, path, options);
        const auto& c = m.config();
        Tensor x({1, c.input_nc, h, w});
        RunInfo info;
        m.run(x, &info);
        m.run(x, &info);
        json ops = json::array();
        double total = 0, flop = 0;
        int launches = 0;
        for (const auto& l : info.layers) {
            ops.push_back({{"name", l.name}, {"kind", l.kind}, {"ms", l.ms}, {"gflop", l.gflop},
                           {"gflops", l.ms > 0 ? l.gflop / (l.ms * 1e-3) : 0.0}, {"launches", l.launches}});
            total += l.ms;
            flop += l.gflop;
            launches += l.launches;
        }
        out["per_op"] = ops;
        out["device_ms_total"] = total;
        out["gflop_total"] = flop;
        out["launches"] = launches;  // kernels per run (+ the input guard's and the transfers, not counted)
    }
    std::printf("%s\n", out.dump(2).c_str());
    return 0;
}

int run_mlp(int argc, char** argv) {
    const std::string path = arg(argc, argv, "--model");
    if (path.empty()) throw InputError("mlp: --model M.safetensors is required");
    const int w = std::stoi(arg(argc, argv, "--width", "1920")), h = std::stoi(arg(argc, argv, "--height", "1080"));
    const int repeats = std::stoi(arg(argc, argv, "--repeats", "5"));
    const bool ao = std::find_if(argv, argv + argc, [](const char* a) { return !std::strcmp(a, "--ao"); }) != argv + argc;
    ModelOptions opt;
    opt.mlp_path = arg(argc, argv, "--path");
    Device d = Device::open(arg(argc, argv, "--device"));
    Context& ctx = ngi::detail::context_of(d);
    const std::size_t hw = std::size_t(w) * h;
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1, 1);
    json out = {{"device", device_json(d, gemm_params_for(d.info()))}, {"width", w}, {"height", h}};
    double macs = 0;
    std::vector<double> ms;
    if (ao) {
        AoNetwork net = AoNetwork::load(d, path, opt);
        int in = net.config().input_nc;
        for (const auto& l : net.config().mlp.layers) macs += double(in) * l.out, in = l.out;
        std::vector<float> n(3 * hw);
        for (std::size_t i = 0; i < hw; ++i) {  // random unit normals, no background
            float x = u(rng), y = u(rng), z = u(rng) + 1e-3f, len = std::sqrt(x * x + y * y + z * z);
            n[i] = x / len, n[hw + i] = y / len, n[2 * hw + i] = z / len;
        }
        DeviceBuffer nb = DeviceBuffer::allocate(d, n.size() * 4), ob = DeviceBuffer::allocate(d, hw * 4);
        nb.upload(n.data(), n.size() * 4);
        std::fprintf(stderr, "ao %s %dx%d: warm-up + %d runs ...\n", path.c_str(), w, h, repeats);
        ms = time_runs(ctx, repeats, [&] { net.enqueue(nb, ob, h, w); });
        out["what"] = "AO network: ring gather + MLP + clamp";
        out["radius_px"] = net.radius_for(h);
    } else {
        Model m = Model::load(d, path, opt);
        int in = m.config().input_nc;
        for (const auto& l : m.config().mlp.layers) macs += double(in) * l.out, in = l.out;
        std::vector<float> x(std::size_t(m.config().input_nc) * hw);
        for (auto& v : x) v = u(rng);
        DeviceBuffer xb = DeviceBuffer::allocate(d, x.size() * 4), yb = DeviceBuffer::allocate(d, std::size_t(in) * hw * 4);
        xb.upload(x.data(), x.size() * 4);
        std::fprintf(stderr, "mlp %s %dx%d: warm-up + %d runs ...\n", path.c_str(), w, h, repeats);
        ms = time_runs(ctx, repeats, [&] { m.enqueue(xb, yb, h, w); });
        out["what"] = "MLP per pixel (Model::enqueue)";
    }
    const double gflop = 2.0 * macs * double(hw) / 1e9;
    out["path"] = opt.mlp_path.empty() ? "auto" : opt.mlp_path;
    out["macs_per_item"] = macs;
    out["gflop"] = gflop;
    out["ms_median"] = median(ms);
    out["ms_all"] = ms;
    out["gflops"] = gflop / (median(ms) * 1e-3);
    std::printf("%s\n", out.dump(2).c_str());
    return 0;
}

// ngi_bench neural-gi's frame: the front face of a camera inside a room that fills the model's scene box (the box
// its positions are normalized with, so every input is in range), one block on the floor (depth and normal edges
// for the upsampling to respect), lit by a ceiling area light; direct light from that light without shadows. The
// timings do not depend on the values except through the upsampling's bilinear fallbacks, which are counted; the
// values are plausible so that the count means something. Also returns the full-resolution guides (world positions
// and normals) for timing the upsampling alone.
struct RoomFrame {
    Frame frame;
    std::vector<float> position, normal;  // [3][n][n]
};

RoomFrame room_frame(int n, const float scene_min[3], const float scene_max[3]) {
    const glm::vec3 lo(scene_min[0], scene_min[1], scene_min[2]), hi(scene_max[0], scene_max[1], scene_max[2]);
    const glm::vec3 extent = hi - lo;
    RoomFrame room;
    Frame& f = room.frame;
    f.n = n;
    f.look = glm::normalize(glm::vec3(0.3f, -0.25f, -1.0f));
    f.up = glm::vec3(0.0f, 1.0f, 0.0f);
    const glm::vec3 eye = lo + extent * glm::vec3(0.45f, 0.45f, 0.85f);
    f.position = eye;
    AreaLight light;
    light.centre = lo + extent * glm::vec3(0.5f, 0.97f, 0.5f);
    light.half_u = glm::vec3(0.1f * extent.x, 0.0f, 0.0f);
    light.half_v = glm::vec3(0.0f, 0.0f, 0.1f * extent.z);  // cross(half_u, half_v) points down: into the room
    light.radiance = glm::vec3(20.0f, 18.0f, 15.0f);
    f.area_light = light;
    for (Feature feature : {Feature::Albedo, Feature::Normal, Feature::Depth, Feature::Direct})
        f.get(feature, Face::Front) = Image(n, n, feature_channels(feature));
    Image& albedo = f.get(Feature::Albedo, Face::Front);
    Image& normal = f.get(Feature::Normal, Face::Front);
    Image& depth = f.get(Feature::Depth, Face::Front);
    Image& direct = f.get(Feature::Direct, Face::Front);
    const glm::vec3 block_lo = lo + extent * glm::vec3(0.3f, 0.0f, 0.25f);
    const glm::vec3 block_hi = lo + extent * glm::vec3(0.55f, 0.3f, 0.5f);
    // Walls -x, +x, -y (floor), +y (ceiling), -z, +z, then the block.
    const glm::vec3 colours[7] = {{0.8f, 0.2f, 0.2f}, {0.2f, 0.7f, 0.2f}, {0.6f, 0.6f, 0.6f}, {0.9f, 0.9f, 0.9f},
                                  {0.7f, 0.7f, 0.6f}, {0.5f, 0.5f, 0.7f}, {0.8f, 0.6f, 0.3f}};
    const FaceBasis basis = CameraCluster::from_look_up(f.look, f.up).face(Face::Front);
    const glm::vec3 light_normal = light.normal();
    const float light_area = light.area(), pi = 3.14159265f;
    const std::size_t plane = std::size_t(n) * n;
    room.position.resize(3 * plane);
    room.normal.resize(3 * plane);
    for (int row = 0; row < n; ++row)
        for (int col = 0; col < n; ++col) {
            // Planar depth t: the point is eye + t d with d the pixel's unnormalized ray (what the renderer writes).
            const glm::vec3 d = face_pixel_direction(basis, col, row, n);
            // The room from inside: the nearest wall along the ray.
            float t = std::numeric_limits<float>::infinity();
            int axis = 0;
            for (int a = 0; a < 3; ++a)
                if (d[a] != 0.0f) {
                    const float ta = ((d[a] > 0.0f ? hi[a] : lo[a]) - eye[a]) / d[a];
                    if (ta < t) t = ta, axis = a;
                }
            int surface = 2 * axis + (d[axis] > 0.0f ? 1 : 0);
            // The block from outside (slabs): entered at the largest entry distance when that precedes every exit.
            float t_in = 0.0f, t_out = std::numeric_limits<float>::infinity();
            int in_axis = -1;
            for (int a = 0; a < 3; ++a) {
                if (d[a] == 0.0f) {
                    if (eye[a] < block_lo[a] || eye[a] > block_hi[a]) t_out = -1.0f;
                    continue;
                }
                float t0 = (block_lo[a] - eye[a]) / d[a], t1 = (block_hi[a] - eye[a]) / d[a];
                if (t0 > t1) std::swap(t0, t1);
                if (t0 > t_in) t_in = t0, in_axis = a;
                t_out = std::min(t_out, t1);
            }
            if (in_axis >= 0 && t_in <= t_out && t_in < t) t = t_in, axis = in_axis, surface = 6;
            glm::vec3 nrm(0.0f);
            nrm[axis] = d[axis] > 0.0f ? -1.0f : 1.0f;  // facing the camera
            const glm::vec3 p = eye + t * d;
            // A small source's irradiance / pi (the lighting buffers' quantity): L A cos cos / (pi r^2).
            const glm::vec3 to_light = light.centre - p;
            const float r2 = glm::dot(to_light, to_light);
            const glm::vec3 w = to_light / std::sqrt(r2);
            const float g = std::max(0.0f, glm::dot(nrm, w)) * std::max(0.0f, -glm::dot(light_normal, w)) *
                            light_area / (pi * r2);
            depth.at(0, row, col) = t;
            for (int c = 0; c < 3; ++c) {
                albedo.at(c, row, col) = colours[surface][c];
                normal.at(c, row, col) = nrm[c];
                direct.at(c, row, col) = light.radiance[c] * g;
                room.position[c * plane + std::size_t(row) * n + col] = p[c];
                room.normal[c * plane + std::size_t(row) * n + col] = nrm[c];
            }
        }
    return room;
}

// Every `stride`-th pixel of a [3][n][n] plane set, the pixel nearest the centre of each block (as the renderer
// samples its low-resolution G-buffer): [3][n / stride][n / stride].
std::vector<float> subsample(const std::vector<float>& planes, int n, int stride) {
    const int side = n / stride;
    std::vector<float> out(3 * std::size_t(side) * side);
    for (int c = 0; c < 3; ++c)
        for (int y = 0; y < side; ++y)
            for (int x = 0; x < side; ++x)
                out[(std::size_t(c) * side + y) * side + x] =
                    planes[(std::size_t(c) * n + y * stride + stride / 2) * n + x * stride + stride / 2];
    return out;
}

int run_neural_gi(int argc, char** argv) {
    const std::string path = arg(argc, argv, "--model");
    if (path.empty()) throw InputError("neural-gi: --model M.safetensors (a neural_gi model with a scene box) is required");
    // "N:K,N:K": face size N, upsampling K. The default: the network at 128 and 256 at full resolution, the same
    // frames with the network at 1/2 and 1/4 where the U-Net can take that size, and the network at 128 and 256
    // upsampled 4x.
    std::vector<std::pair<int, int>> frames;
    for (const std::string& pair : split(arg(argc, argv, "--frames", "128:1,128:2,128:4,256:1,256:2,256:4,512:4,1024:4"))) {
        const std::size_t colon = pair.find(':');
        if (colon == std::string::npos) throw InputError("neural-gi: --frames takes N:K pairs, got '" + pair + "'");
        frames.emplace_back(std::stoi(pair.substr(0, colon)), std::stoi(pair.substr(colon + 1)));
    }
    const int repeats = std::stoi(arg(argc, argv, "--repeats", "5"));
    const std::string device_spec = arg(argc, argv, "--device");

    Device d = Device::open(device_spec);
    Context& ctx = ngi::detail::context_of(d);
    Model model = Model::load(d, path);
    const ModelConfig& c = model.config();
    if (c.family != "neural_gi" || !c.neural_gi.has_scene_box)
        throw InputError("neural-gi: " + path + " is not a neural_gi model with a scene box");
    NeuralGiRenderer renderer(d);
    JointBilateralUpsample jbu(ctx);
    const JbuParams jbu_params;  // NeuralGiOptions' defaults
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    const int step = 1 << c.unet.num_downs;
    std::vector<int> network_sides;
    json cases = json::array();
    RoomFrame room;
    for (const auto& [n, k] : frames) {
        json row = {{"n", n}, {"upsample", k}};
        if (n < 1 || k < 1 || n % k || (n / k) % step) {
            row["skipped"] = "the network would run at " + std::to_string(n) + " / " + std::to_string(k) +
                             ", which is not a positive multiple of 2^num_downs = " + std::to_string(step);
            std::fprintf(stderr, "neural-gi N %d, upsample %d: skipped (%s)\n", n, k,
                         row["skipped"].get<std::string>().c_str());
            cases.push_back(row);
            continue;
        }
        if (room.frame.n != n) room = room_frame(n, c.neural_gi.scene_min, c.neural_gi.scene_max);
        const int side = n / k;
        if (std::find(network_sides.begin(), network_sides.end(), side) == network_sides.end())
            network_sides.push_back(side);
        std::fprintf(stderr, "neural-gi N %d, upsample %d (network at %d): warm-up + %d runs ...\n", n, k, side,
                     repeats);
        NeuralGiOptions options;
        options.upsample = k;
        NeuralGiImages images;
        const auto frame_ms = time_runs(ctx, repeats, [&] { images = renderer.run(model, room.frame, options); });
        row["network_side"] = side;
        row["frame_ms_median"] = median(frame_ms);
        row["frame_ms_all"] = frame_ms;
        row["jbu_fallback_pixels"] = images.jbu_fallbacks;
        row["sanitized_inputs"] = images.sanitized_inputs;

        // The network alone at N / K, input and output on the device (what the frame spends in it).
        std::vector<float> x(std::size_t(c.input_nc) * side * side);
        for (auto& v : x) v = u(rng);
        DeviceBuffer xb = DeviceBuffer::allocate(d, x.size() * sizeof(float));
        DeviceBuffer yb = DeviceBuffer::allocate(d, std::size_t(c.output_nc) * side * side * sizeof(float));
        xb.upload(x.data(), x.size() * sizeof(float));
        const auto network_ms = time_runs(ctx, repeats, [&] { model.enqueue(xb, yb, side, side); });
        row["network_ms_median"] = median(network_ms);
        row["network_ms_all"] = network_ms;

        if (k > 1) {  // The upsampling alone: the frame's guides at both resolutions, random indirect light.
            std::vector<float> low(3 * std::size_t(side) * side);
            for (auto& v : low) v = 1.0f + u(rng);
            const Buffer low_b = upload_floats(ctx, low, "bench JBU low"),
                         low_normal = upload_floats(ctx, subsample(room.normal, n, k), "bench JBU low normals"),
                         low_position = upload_floats(ctx, subsample(room.position, n, k), "bench JBU low positions"),
                         normal = upload_floats(ctx, room.normal, "bench JBU normals"),
                         position = upload_floats(ctx, room.position, "bench JBU positions");
            const Buffer out = ctx.alloc(3 * std::size_t(n) * n * sizeof(float), "bench JBU out");
            JbuInputs in;
            in.low_width = in.low_height = side;
            in.channels = 3;
            in.low = low_b.get();
            in.low_normal = low_normal.get();
            in.low_position = low_position.get();
            in.width = in.height = n;
            in.normal = normal.get();
            in.position = position.get();
            const auto jbu_ms = time_runs(ctx, repeats, [&] { jbu.enqueue(ctx, in, jbu_params, out.get(), false); });
            row["jbu_ms_median"] = median(jbu_ms);
            row["jbu_ms_all"] = jbu_ms;
        }
        std::fprintf(stderr, "neural-gi N %d, upsample %d: frame %.1f ms, network at %d %.1f ms, upsampling %.1f ms\n",
                     n, k, median(frame_ms), side, median(network_ms), row.value("jbu_ms_median", 0.0));
        cases.push_back(row);
    }

    json network_profile = json::object();
    if (!has_flag(argc, argv, "--no-profile")) {
        // Device time per op of one profiled run per network size (after a warm-up run), timed apart from the wall
        // times above (profiling can perturb them); also the network's device memory.
        Device pd = Device::open(device_spec, DeviceOptions{true});
        Model pm = Model::load(pd, path);
        for (const int side : network_sides) {
            std::fprintf(stderr, "neural-gi: profiled network run at %d ...\n", side);
            Tensor x({1, c.input_nc, side, side});
            for (auto& v : x.data) v = u(rng);
            RunInfo info;
            pm.run(x, &info);
            pm.run(x, &info);
            double total = 0, gflop = 0;
            json by_kind = json::object();
            for (const auto& l : info.layers) {
                total += l.ms;
                gflop += l.gflop;
                by_kind[l.kind] = by_kind.value(l.kind, 0.0) + l.ms;
            }
            network_profile[std::to_string(side)] = {
                {"device_ms_total", total}, {"device_ms_by_kind", by_kind}, {"gflop", gflop},
                {"memory_mib", {{"weights", info.weight_bytes / 1048576.0}, {"arena", info.arena_bytes / 1048576.0},
                                {"scratch", info.scratch_bytes / 1048576.0}}}};
        }
    }

    const json model_json = {
        {"file", std::filesystem::path(path).filename().string()}, {"family", c.family}, {"ngf", c.unet.ngf},
        {"num_downs", c.unet.num_downs}, {"bn_mode", c.unet.bn_mode}, {"buffer_channels", c.neural_gi.buffer_channels},
        {"mlp_width", c.neural_gi.mlp_width}, {"mlp_depth", c.neural_gi.mlp_depth},
        {"skip_layer", c.neural_gi.skip_layer},
        {"scene_box", {{"min", std::vector<float>(c.neural_gi.scene_min, c.neural_gi.scene_min + 3)},
                       {"max", std::vector<float>(c.neural_gi.scene_max, c.neural_gi.scene_max + 3)}}}};
    const json out = {
        {"device", device_json(d, gemm_params_for(d.info()))},
        {"model", model_json},
        {"frame", "synthetic: a room filling the model's scene box, one block, a ceiling area light, unshadowed "
                  "direct light (perf/ngi_bench.cpp room_frame)"},
        {"repeats", repeats},
        {"timing", "frame: NeuralGiRenderer::run wall time (uploads, inputs, network, upsampling, lighting, two "
                   "downloads); network: Model::enqueue at N/K + finish; jbu: the upsampling kernel + finish; medians "
                   "after one warm-up"},
        {"cases", cases},
        {"network_profile", network_profile}};
    std::printf("%s\n", out.dump(2).c_str());
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    const std::string cmd = argc > 1 ? argv[1] : "";
    try {
        if (cmd == "gemm") return run_gemm(argc, argv);
        if (cmd == "tune") return run_tune(argc, argv);
        if (cmd == "generator") return run_generator(argc, argv);
        if (cmd == "conv") return run_conv(argc, argv);
        if (cmd == "mlp") return run_mlp(argc, argv);
        if (cmd == "neural-gi") return run_neural_gi(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "ngi_bench %s: error: %s\n", cmd.c_str(), e.what());
        return 1;
    }
    std::fprintf(stderr, "usage: ngi_bench gemm|tune|conv|generator|mlp|neural-gi [options]  (see the comment at the top of "
                         "perf/ngi_bench.cpp)\n");
    return 2;
}
