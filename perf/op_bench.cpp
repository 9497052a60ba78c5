// op_bench: every op of host/src/ops/ timed at perf-sized shapes, from the op harness's table (tests/op_harness/):
// the same rows the correctness test runs, at Size::Perf. Prints one JSON object (stdout, or --out), progress on
// stderr.
//
//   op_bench [--device D] [--repeats N] [--only op,...] [--out f.json]
//
// --only keeps the rows whose op starts with one of the given names ("Gemm", "Conv2d::enqueue", ...). Per row: one
// warm-up run (PoCL compiles a work-group function at a kernel's first launch), then N runs, each bounded by
// clFinish; the median wall time, GFLOP/s from the row's FLOPs and GB/s from the bytes it must move at least. The
// tiny rows (oclgrind's) are skipped. After the runs the guards of every buffer are checked once more.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench_args.hpp"
#include "ngi/device.hpp"
#include "op_harness/op_cases.hpp"
#include "runtime/context.hpp"

using json = nlohmann::json;
using ngi_perf::arg;
using ngi_perf::split;

int main(int argc, char** argv) {
    try {
        const int repeats = std::max(1, std::stoi(arg(argc, argv, "--repeats", "5")));
        const std::vector<std::string> only = split(arg(argc, argv, "--only", ""));
        const std::string out_path = arg(argc, argv, "--out", "");
        ngi::Device device = ngi::Device::open(arg(argc, argv, "--device", ""));
        ngi::detail::Context& ctx = ngi::detail::context_of(device);

        json out = {{"device", device.info().name}, {"platform", device.info().platform_name},
                    {"repeats", repeats}, {"results", json::array()}};
        int failures = 0;
        for (const ngi::harness::OpCase& c : ngi::harness::op_cases()) {
            if (c.tiny) continue;
            if (!only.empty() && std::none_of(only.begin(), only.end(),
                                              [&](const std::string& o) { return c.op.rfind(o, 0) == 0; }))
                continue;
            std::mt19937 rng = ngi::harness::case_rng(c);  // as the test: rows that draw their shapes draw the same
            ngi::harness::Prepared p = c.prepare(ctx, ngi::harness::Size::Perf, rng);
            std::fprintf(stderr, "%s [%s]\n", c.id().c_str(), p.shape.c_str());
            p.run(ctx);  // warm-up
            ctx.finish();
            std::vector<double> ms;
            for (int k = 0; k < repeats; ++k) {
                const auto t0 = std::chrono::steady_clock::now();
                p.run(ctx);
                ctx.finish();
                ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
            }
            std::sort(ms.begin(), ms.end());
            const double median = ms[ms.size() / 2];
            std::string damaged;
            for (const auto& b : p.buffers)
                if (damaged.empty()) damaged = b->check(ctx, c.id());
            if (!damaged.empty()) {
                std::fprintf(stderr, "guard check failed: %s\n", damaged.c_str());
                ++failures;
            }
            out["results"].push_back({{"op", c.op}, {"case", c.name}, {"shape", p.shape}, {"ms", median},
                                      {"ms_min", ms.front()}, {"gflops", p.flops / (median * 1e6)},
                                      {"gbps", p.bytes / (median * 1e6)}, {"guards_intact", damaged.empty()}});
        }
        const std::string text = out.dump(2) + "\n";
        if (out_path.empty()) {
            std::fputs(text.c_str(), stdout);
        } else {
            std::ofstream f(out_path);
            f << text;
            if (!f) throw std::runtime_error("cannot write " + out_path);
        }
        return failures ? 1 : 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "op_bench: %s\n", e.what());
        return 1;
    }
}
