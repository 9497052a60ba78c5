#include <algorithm>
#include <chrono>
#include <cstdio>

#include "commands.hpp"
#include "ngi/model.hpp"

namespace ngi_cli {

int cmd_generate(int argc, char** argv) {
    Args args(argc, argv, 2, {"profile"}, {"model", "input", "output", "device", "bn-mode", "dropout", "mlp-path"});
    no_positionals(args);
    const std::string model_path = args.require("model"), input_path = args.require("input"),
                      output_path = args.require("output");
    ngi::DeviceOptions dopt;
    dopt.profiling = args.has("profile");
    ngi::Device device = ngi::Device::open(args.get("device"), dopt);
    ngi::ModelOptions mopt{args.get("bn-mode"), args.get("dropout"), args.get("mlp-path")};

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
    if (c.family == "mlp") {
        std::string widths;
        for (const auto& l : c.layers) widths += (widths.empty() ? "" : "-") + std::to_string(l.out) + " " + l.activation;
        std::printf("model      %s: mlp, %d inputs, encoding %d bands, layers %s\n", model_path.c_str(), c.input_nc,
                    c.encoding_bands, widths.c_str());
    } else {
        std::printf("model      %s: %s, %d -> %d channels, ngf %d, %d downs, bn %s, dropout %s\n", model_path.c_str(),
                    c.family.c_str(), c.input_nc, c.output_nc, c.ngf, c.num_downs, c.bn_mode.c_str(), c.dropout.c_str());
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
    if (args.has("profile")) {
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

}  // namespace ngi_cli
