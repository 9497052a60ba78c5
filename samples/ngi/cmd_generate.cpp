#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "commands.hpp"
#include "ngi/model.hpp"

namespace ngi_cli {

namespace {

struct Options {
    std::string model_path, input_path, output_path, device;
    bool profile = false;
    ngi::ModelOptions model;  // "": the model's own setting
};

int run(const Options& o) {
    const std::string model_path = ngi::resolve_model(o.model_path);  // a file, or a shipped model's name
    const std::string &input_path = o.input_path, &output_path = o.output_path;
    ngi::DeviceOptions dopt;
    dopt.profiling = o.profile;
    ngi::Device device = ngi::Device::open(o.device, dopt);
    const ngi::ModelOptions& mopt = o.model;

    auto t0 = std::chrono::steady_clock::now();
    ngi::Model model = ngi::Model::load(device, model_path, mopt);
    const ngi::Tensor x = ngi::read_npy(input_path);
    auto t1 = std::chrono::steady_clock::now();
    ngi::RunInfo info;
    const ngi::Tensor y = model.run(x, &info);
    auto t2 = std::chrono::steady_clock::now();
    ngi::write_npy(output_path, y);

    const auto& c = model.config();
    auto ms = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
    std::printf("device     %s\n", device.info().name.c_str());
    // What the model's config holds, by its sections (not by its family's name): a dense-layer list (mlp), a U-Net
    // (the generators), or neither (the family and its channels).
    if (!c.mlp.layers.empty()) {
        std::string widths;
        for (const auto& l : c.mlp.layers) widths += (widths.empty() ? "" : "-") + std::to_string(l.out) + " " + l.activation;
        std::printf("model      %s: %s, %d inputs, encoding %d bands, layers %s\n", model_path.c_str(),
                    c.family.c_str(), c.input_nc, c.encoding.bands, widths.c_str());
    } else if (c.unet.ngf > 0) {
        std::printf("model      %s: %s, %d -> %d channels, ngf %d, %d downs, bn %s, dropout %s\n", model_path.c_str(),
                    c.family.c_str(), c.input_nc, c.output_nc, c.unet.ngf, c.unet.num_downs, c.unet.bn_mode.c_str(),
                    c.unet.dropout.c_str());
    } else {
        std::printf("model      %s: %s, %d -> %d channels\n", model_path.c_str(), c.family.c_str(), c.input_nc,
                    c.output_nc);
    }
    std::printf("input      %s %s\n", input_path.c_str(), ngi::shape_string(x.shape).c_str());
    std::printf("output     %s %s\n", output_path.c_str(), ngi::shape_string(y.shape).c_str());
    std::printf("time       load %.1f ms, first run %.1f ms (includes graph planning and kernel warm-up)\n",
                ms(t0, t1), ms(t1, t2));
    std::printf("memory     weights %.1f MiB, tensor arena %.1f MiB (without reuse %.1f MiB), scratch %.1f MiB\n",
                info.weight_bytes / 1048576.0, info.arena_bytes / 1048576.0, info.naive_bytes / 1048576.0,
                info.scratch_bytes / 1048576.0);
    if (info.sanitized_inputs)  // on stderr, so that it is seen even when the report is redirected
        std::fprintf(stderr, "ngi generate: warning: %d of %zu input values were NaN, infinite or outside the model's "
                     "input range [%g, %g] and were replaced (NaN -> 0, others clamped to the range)\n",
                     info.sanitized_inputs, x.data.size(), double(c.input_range[0]), double(c.input_range[1]));
    // Every non-finite output is counted and reported (issue 51: weights near 3e38 once wrote 256 of 256 Inf with
    // no word). The file is still written: it is what the model computes.
    std::size_t nonfinite = 0;
    for (float v : y.data) nonfinite += !std::isfinite(v);
    if (nonfinite)
        std::fprintf(stderr, "ngi generate: warning: %zu of %zu output values are NaN or infinite (the model's weights or "
                     "its input overflow float; %s holds them as computed)\n",
                     nonfinite, y.data.size(), output_path.c_str());
    std::printf("nonfinite  %zu of %zu output values\n", nonfinite, y.data.size());
    if (o.profile) {
        double total = 0;
        for (const auto& l : info.layers) total += l.ms;
        std::printf("\n%-28s %-22s %10s %10s %9s\n", "node", "kind", "ms", "GFLOP", "GFLOP/s");
        for (const auto& l : info.layers)
            std::printf("%-28s %-22s %10.3f %10.3f %9.1f\n", l.name.c_str(), l.kind.c_str(), l.ms, l.gflop,
                        l.ms > 0 ? l.gflop / (l.ms * 1e-3) : 0.0);
        std::printf("%-28s %-22s %10.3f\n", "total (device time)", "", total);
    }
    return 0;
}

}  // namespace

Run add_generate(CLI::App& app) {
    auto o = std::make_shared<Options>();
    CLI::App* cmd = add_command(app, "generate", "run a generator or an mlp on a NumPy float32 tensor",
                                "A generator takes an NCHW tensor with N = 1; an mlp takes one point per pixel "
                                "([1, C, H, W]) or per row ([N, C]).");
    add_path(*cmd, "--model", o->model_path, "M", "the model: a .safetensors file or a shipped model's name (surround)",
             true);
    add_path(*cmd, "--input", o->input_path, "X.npy", "the input tensor", true);
    add_path(*cmd, "--output", o->output_path, "Y.npy", "the output tensor to write", true);
    add_device(*cmd, o->device);
    add_switch(*cmd, "--profile", o->profile, "also print the device time of every layer");
    add_choice(*cmd, "--bn-mode", o->model.bn_mode, {"running", "per_image"},
               "batch norm statistics: running (the trained ones) or per_image", "the model's");
    add_choice(*cmd, "--dropout", o->model.dropout, {"off", "seeded"}, "dropout at inference", "the model's");
    add_choice(*cmd, "--mlp-path", o->model.mlp_path, {"fused", "dense"}, "an mlp's kernels (mlp models only)",
               "fused when the network fits the device");
    return [o] { return run(*o); };
}

}  // namespace ngi_cli
