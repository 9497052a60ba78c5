// frame_bench: the whole frame path with a real generator (preprocess, merge, coordinate map, generator, front-view
// extraction, decode, compose, tone map) three ways, side by side in one run at each face size:
//   step    the step-by-step calls with host tensors and images between them (the path before enqueue/run)
//   host    SurroundPipeline::run: host planes in, host images out (one upload, one download)
//   device  SurroundPipeline::enqueue on device buffers + Device::finish (no host transfer)
// Each repetition runs the three in turn (so machine noise hits all of them alike); medians and minima of the
// wall-clock per frame, and the host transfers (count and bytes) of one frame of each path. Prints JSON.
//
//   frame_bench [--device D] [--model models/surround.safetensors] [--n 64,128,256] [--runs 9]
//
// --display S (issue 50): the whole displayed frame instead, device in and device out: SurroundPipeline::enqueue at
// each N (preprocess, merge, the rung -- a network or the ssgi gather --, decode, compose) and then ngi::DisplayView
// at S x S (guides, upsampling, temporal accumulation, compose, tone map; docs/CONVENTIONS.md section 20). Reported
// per stage (medians of runs with stage timings, where each stage waits for the device) and for the whole frame
// (medians of runs without: one enqueue of each, one finish). 960^2 has the pixels of 1280 x 720. --frame DIR: a
// rendered frame folder as the N x N input (the ssgi gather's cost depends on the scene; default: a synthetic frame);
// --display-frame DIR: the same view rendered at S x S as the display face (ngi render --face S --spp 1 --feature-spp 1;
// a real frame's geometry: the JBU's bilinear fallback, one pixel at a time, is rare there); default: a synthetic
// face of random values, where many pixels take that fallback (an upper bound for the upsampling). --jbu-radius R:
// the display view's JBU radius (default DisplaySettings': 2; 1 is the fast setting, docs/RESULTS.md measures both).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench_frame.hpp"
#include "ngi/device_buffer.hpp"
#include "ngi/display.hpp"
#include "ngi/error.hpp"
#include "ngi/image_io.hpp"
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

double median_of(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

// --display S: the whole displayed frame per stage and in one piece (see the top of the file).
nlohmann::json displayed_frame(const ngi::Device& device, ngi::Model& model, const ngi::Frame& low, int display,
                               int runs, const ngi::Frame* rendered_display, int jbu_radius) {
    // All six faces, as an engine hands them over: every rung reads what it needs of them (a front-only rung face 0).
    const int n = low.n, faces = ngi::kFaceCount;
    ngi::SurroundPipeline pl(device, n);
    const std::vector<float> planes = ngi::pack_frame_planes(low, faces);
    ngi::DeviceBuffer in = ngi::DeviceBuffer::allocate(device, planes.size() * sizeof(float));
    in.upload(planes.data(), in.bytes());
    ngi::FrameOutputs outs;
    outs.lightmap = ngi::DeviceBuffer::allocate(device, 3 * std::size_t(n) * n * sizeof(float));
    const ngi::FrameDesc desc = ngi::FrameDesc::of(low, faces);

    std::mt19937 rng(2);
    ngi::Frame hi = rendered_display ? *rendered_display : ngi_bench::synthetic_frame(2, rng);
    if (rendered_display && (hi.n != display || hi.look != low.look || hi.up != low.up))
        throw std::runtime_error("--display-frame: not the --frame's view at the --display size");
    hi.n = display;
    hi.look = low.look;
    hi.up = low.up;
    std::mt19937 rng_hi(3);
    for (int fi = 0; fi < ngi::kFeatureCount && !rendered_display; ++fi) {  // synthetic: face 0 replaced at S x S
        const ngi::Feature f = ngi::Feature(fi);
        ngi::Image im(display, display, ngi::feature_channels(f));
        std::uniform_real_distribution<float> u(0.0f, f == ngi::Feature::Depth ? 20.0f : 1.0f);
        for (float& v : im.data) v = u(rng_hi);
        hi.get(f, ngi::Face::Front) = std::move(im);
    }
    const std::vector<float> hi_planes = ngi::pack_frame_planes(hi, 1);
    ngi::DeviceBuffer hi_in = ngi::DeviceBuffer::allocate(device, hi_planes.size() * sizeof(float));
    hi_in.upload(hi_planes.data(), hi_in.bytes());
    const ngi::FrameDesc hi_desc = ngi::FrameDesc::of(hi, 1);
    ngi::FrameOutputs shown;
    shown.display = ngi::DeviceBuffer::allocate(device, 3 * std::size_t(display) * display * sizeof(float));
    ngi::DisplaySettings settings;
    if (jbu_radius > 0) settings.radius = jbu_radius;
    ngi::DisplayView view(device, display, settings);
    const glm::vec3 position(0.0f);

    auto frame = [&](ngi::FrameTimings* ft, ngi::DisplayTimings* dt) {
        pl.enqueue(model, in, desc, outs, nullptr, ft);
        view.enqueue(n, in, outs.lightmap, hi_in, hi_desc, position, shown, nullptr, dt);
        device.finish();
    };
    for (int w = 0; w < 3; ++w) frame(nullptr, nullptr);  // builds, buffers, and the history the temporal pass reads
    std::vector<double> whole, stage[8];
    for (int r = 0; r < runs; ++r) {
        const double t0 = now_ms();
        frame(nullptr, nullptr);
        whole.push_back(now_ms() - t0);
        ngi::FrameTimings ft;
        ngi::DisplayTimings dt;
        frame(&ft, &dt);
        const double v[8] = {ft.gather_ms, ft.input_ms, ft.network_ms, ft.outputs_ms,
                             dt.geometry_ms, dt.upsample_ms, dt.temporal_ms, dt.outputs_ms};
        for (int k = 0; k < 8; ++k) stage[k].push_back(v[k]);
    }
    const char* names[8] = {"gather", "preprocess_merge", "rung", "decode_compose",
                            "display_guides", "display_upsample", "display_temporal", "display_compose_tonemap"};
    nlohmann::json st = nlohmann::json::object();
    double sum = 0;
    for (int k = 0; k < 8; ++k) {
        st[names[k]] = median_of(stage[k]);
        sum += median_of(stage[k]);
    }
    return {{"n", n}, {"display", display}, {"display_pixels", std::size_t(display) * display},
            {"jbu_radius", settings.radius},
            {"frame_median_ms", median_of(whole)}, {"frame_min_ms", *std::min_element(whole.begin(), whole.end())},
            {"stages_median_ms", st}, {"stages_sum_ms", sum},
            {"display_share_of_stages", (median_of(stage[4]) + median_of(stage[5]) + median_of(stage[6]) +
                                         median_of(stage[7])) / std::max(sum, 1e-9)}};
}

}  // namespace

int main(int argc, char** argv) {
    std::string device_spec, sizes = "64,128,256", model_path = "models/surround.safetensors", frame_dir, display_dir;
    int runs = 9, display = 0, jbu_radius = 0;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--device")) device_spec = argv[i + 1];
        else if (!std::strcmp(argv[i], "--n")) sizes = argv[i + 1];
        else if (!std::strcmp(argv[i], "--runs")) runs = std::max(1, std::atoi(argv[i + 1]));
        else if (!std::strcmp(argv[i], "--model")) model_path = argv[i + 1];
        else if (!std::strcmp(argv[i], "--display")) display = std::atoi(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--frame")) frame_dir = argv[i + 1];
        else if (!std::strcmp(argv[i], "--display-frame")) display_dir = argv[i + 1];
        else if (!std::strcmp(argv[i], "--jbu-radius")) jbu_radius = std::atoi(argv[i + 1]);
        else {
            std::fprintf(stderr, "usage: frame_bench [--device D] [--model M] [--n 64,128,256] [--runs 9] "
                                 "[--display S [--frame DIR [--display-frame DIR]] [--jbu-radius R]]\n");
            return 2;
        }
    }
    try {
        const ngi::Device device = ngi::Device::open(device_spec);
        ngi::Model model = ngi::Model::load(device, model_path);
        if (display > 0) {
            nlohmann::json out = {{"device", device.info().name}, {"driver", device.info().driver_version},
                                  {"model", model_path}, {"runs", runs}, {"frame", frame_dir.empty() ? "synthetic" : frame_dir},
                                  {"display_frame", display_dir.empty() ? "synthetic" : display_dir},
                                  {"displayed", nlohmann::json::array()}};
            std::mt19937 rng(1);
            if (!display_dir.empty() && frame_dir.empty())
                throw std::runtime_error("--display-frame needs --frame (the same view at N)");
            if (!frame_dir.empty()) {
                const ngi::Frame shown = display_dir.empty() ? ngi::Frame{} : ngi::read_frame(display_dir);
                out["displayed"].push_back(displayed_frame(device, model, ngi::read_frame(frame_dir), display, runs,
                                                           display_dir.empty() ? nullptr : &shown, jbu_radius));
            } else {
                for (int n : ngi_bench::parse_sizes(sizes))
                    out["displayed"].push_back(displayed_frame(device, model, ngi_bench::synthetic_frame(n, rng),
                                                               display, runs, nullptr, jbu_radius));
            }
            std::printf("%s\n", out.dump(2).c_str());
            return 0;
        }
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
