// pipeline_bench: per-frame cost of the surround-aware pipeline around the generator (everything but the
// model): preprocessing + merge (network_input), front-view extraction + decode (front_lightmap), compose and
// tone map, at several face sizes. Wall-clock per call, host transfers included (each call returns host data).
// Warm-up first, then the median and minimum of --runs runs. Prints JSON.
//
//   pipeline_bench [--device cpu|gpu|P:D] [--n 128,256] [--runs 9] [--mode thesis|equirect]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "ngi/error.hpp"
#include "bench_frame.hpp"
#include "ngi/pipeline.hpp"

using ngi_bench::parse_sizes;
using ngi_bench::synthetic_frame;

namespace {

struct Timing {
    double median_ms, min_ms;
};

Timing measure(int runs, const std::function<void()>& fn) {
    fn();  // warm-up: kernel builds, buffer allocation, first-touch
    std::vector<double> ms;
    for (int i = 0; i < runs; ++i) {
        const auto t0 = std::chrono::steady_clock::now();
        fn();
        ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    std::sort(ms.begin(), ms.end());
    return {ms[ms.size() / 2], ms.front()};
}

}  // namespace

int main(int argc, char** argv) {
    std::string device_spec, sizes = "128,256", mode_name = "thesis";
    int runs = 9;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--device")) device_spec = argv[i + 1];
        else if (!std::strcmp(argv[i], "--n")) sizes = argv[i + 1];
        else if (!std::strcmp(argv[i], "--runs")) runs = std::max(1, std::atoi(argv[i + 1]));
        else if (!std::strcmp(argv[i], "--mode")) mode_name = argv[i + 1];
        else {
            std::fprintf(stderr, "usage: pipeline_bench [--device D] [--n 128,256] [--runs 9] [--mode thesis|equirect]\n");
            return 2;
        }
    }
    try {
        const ngi::Device device = ngi::Device::open(device_spec);
        const ngi::GlobalViewMode mode = ngi::global_view_mode_from_name(mode_name);
        nlohmann::json out = {{"device", device.info().name},
                              {"driver", device.info().driver_version},
                              {"mode", mode_name},
                              {"runs", runs},
                              {"sizes", nlohmann::json::array()}};
        std::mt19937 rng(1);
        for (int n : parse_sizes(sizes)) {
            const auto t0 = std::chrono::steady_clock::now();
            ngi::SurroundPipeline pl(device, n, mode);
            const double setup_ms =
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
            const ngi::Frame frame = synthetic_frame(n, rng);
            ngi::ModelConfig cfg;
            cfg.input_nc = 12;
            cfg.output_nc = 3;
            // Stand-in for the generator's output: its lumination planes (same shape and range as a lightmap).
            ngi::Tensor x = pl.network_input(frame, cfg);
            ngi::Tensor y({1, 3, 2 * n, 4 * n});
            std::memcpy(y.data.data(), &x.data[7 * y.size() / 3], y.size() * sizeof(float));
            ngi::Image light = pl.front_lightmap(y, cfg), final_image = pl.compose(light, frame);

            const Timing pre = measure(runs, [&] { x = pl.network_input(frame, cfg); });
            const Timing ext = measure(runs, [&] { light = pl.front_lightmap(y, cfg); });
            const Timing comp = measure(runs, [&] { final_image = pl.compose(light, frame); });
            const Timing tm = measure(runs, [&] { pl.tonemap(final_image); });
            const Timing all = measure(runs, [&] {
                x = pl.network_input(frame, cfg);
                light = pl.front_lightmap(y, cfg);
                pl.tonemap(pl.compose(light, frame));
            });
            auto j = [](const Timing& t) { return nlohmann::json{{"median_ms", t.median_ms}, {"min_ms", t.min_ms}}; };
            out["sizes"].push_back({{"n", n},
                                    {"global_view", {4 * n, 2 * n}},
                                    {"setup_ms", setup_ms},
                                    {"network_input", j(pre)},
                                    {"front_lightmap", j(ext)},
                                    {"compose", j(comp)},
                                    {"tonemap", j(tm)},
                                    {"frame_total", j(all)}});
        }
        std::printf("%s\n", out.dump(2).c_str());
    } catch (const ngi::Error& e) {
        std::fprintf(stderr, "pipeline_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
