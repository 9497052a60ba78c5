// frame_bench: the whole frame path with a real generator (preprocess, merge, coordinate map, generator, front-view
// extraction, decode, compose, tone map) three ways, side by side in one run at each face size:
//   step    the step-by-step calls with host tensors and images between them (the path before enqueue/run)
//   host    SurroundPipeline::run: host planes in, host images out (one upload, one download)
//   device  SurroundPipeline::enqueue on device buffers + Device::finish (no host transfer)
// Each repetition runs the three in turn (so machine noise hits all of them alike); medians and minima of the
// wall-clock per frame, and the host transfers (count and bytes) of one frame of each path. Prints JSON.
//
//   frame_bench [--device D] [--model models/surround.safetensors] [--n 64,128,256] [--runs 9]
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

#include "bench_frame.hpp"
#include "ngi/device_buffer.hpp"
#include "ngi/error.hpp"
#include "ngi/model.hpp"
#include "ngi/pipeline.hpp"

namespace {

double now_ms() {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

nlohmann::json summary(std::vector<double> ms, const ngi::HostTransfers& t) {
    std::sort(ms.begin(), ms.end());
    return {{"median_ms", ms[ms.size() / 2]},
            {"min_ms", ms.front()},
            {"uploads", t.uploads},
            {"downloads", t.downloads},
            {"upload_bytes", t.upload_bytes},
            {"download_bytes", t.download_bytes}};
}

}  // namespace

int main(int argc, char** argv) {
    std::string device_spec, sizes = "64,128,256", model_path = "models/surround.safetensors";
    int runs = 9;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--device")) device_spec = argv[i + 1];
        else if (!std::strcmp(argv[i], "--n")) sizes = argv[i + 1];
        else if (!std::strcmp(argv[i], "--runs")) runs = std::max(1, std::atoi(argv[i + 1]));
        else if (!std::strcmp(argv[i], "--model")) model_path = argv[i + 1];
        else {
            std::fprintf(stderr, "usage: frame_bench [--device D] [--model M] [--n 64,128,256] [--runs 9]\n");
            return 2;
        }
    }
    try {
        const ngi::Device device = ngi::Device::open(device_spec);
        ngi::Model model = ngi::Model::load(device, model_path);
        const bool surround = model.config().input_nc == 12;
        const int faces = surround ? ngi::kFaceCount : 1;
        nlohmann::json out = {{"device", device.info().name}, {"driver", device.info().driver_version},
                              {"model", model_path}, {"runs", runs}, {"sizes", nlohmann::json::array()}};
        std::mt19937 rng(1);
        for (int n : ngi_bench::parse_sizes(sizes)) {
            std::fprintf(stderr, "frame_bench: N = %d ...\n", n);
            ngi::SurroundPipeline pl(device, n);
            const ngi::Frame frame = ngi_bench::synthetic_frame(n, rng);
            const ngi::ToneMapOptions tm;
            const std::size_t out_bytes = 3 * std::size_t(n) * n * sizeof(float);
            const std::vector<float> planes = ngi::pack_frame_planes(frame, faces);
            ngi::DeviceBuffer in = ngi::DeviceBuffer::allocate(device, planes.size() * sizeof(float));
            in.upload(planes.data(), in.bytes());
            ngi::FrameOutputs outs;
            outs.lightmap = ngi::DeviceBuffer::allocate(device, out_bytes);
            outs.final_image = ngi::DeviceBuffer::allocate(device, out_bytes);
            outs.display = ngi::DeviceBuffer::allocate(device, out_bytes);
            const ngi::FrameDesc desc = ngi::FrameDesc::of(frame, faces);

            const std::function<void()> paths[3] = {
                [&] {
                    // With the frame: an indirect-mode model's lightmap adds the frame's direct light.
                    const ngi::Image light = pl.front_lightmap(model.run(pl.network_input(frame, model.config())),
                                                               model.config(), frame);
                    pl.tonemap(pl.compose(light, frame), tm);
                },
                [&] { pl.run(model, frame, true, true, true, tm); },
                [&] {
                    pl.enqueue(model, in, desc, outs);
                    device.finish();
                }};
            std::vector<double> ms[3];
            ngi::HostTransfers per_frame[3];
            for (int p = 0; p < 3; ++p) {  // warm-up (kernel builds, graph planning, buffers), then one counted frame
                paths[p]();
                const ngi::HostTransfers t0 = device.host_transfers();
                paths[p]();
                const ngi::HostTransfers t1 = device.host_transfers();
                per_frame[p] = {t1.uploads - t0.uploads, t1.downloads - t0.downloads, t1.upload_bytes - t0.upload_bytes,
                                t1.download_bytes - t0.download_bytes};
            }
            for (int r = 0; r < runs; ++r)
                for (int p = 0; p < 3; ++p) {
                    const double t0 = now_ms();
                    paths[p]();
                    ms[p].push_back(now_ms() - t0);
                }
            out["sizes"].push_back({{"n", n},
                                    {"step", summary(ms[0], per_frame[0])},
                                    {"host", summary(ms[1], per_frame[1])},
                                    {"device", summary(ms[2], per_frame[2])}});
        }
        std::printf("%s\n", out.dump(2).c_str());
    } catch (const ngi::Error& e) {
        std::fprintf(stderr, "frame_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
