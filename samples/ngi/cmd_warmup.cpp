#include <chrono>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "ngi/model.hpp"
#include "ngi/warmup.hpp"

namespace ngi_cli {

namespace {

struct Options {
    std::string models = "ssgi_surround", device;
    int n = 64, display = 0;
    bool json = false;
};

// Loads each model and runs ngi::warm_up on it: every program its frame (and display view) needs is built into the
// program cache now, so that later processes start fast. A second run reports 0 programs built.
int run(const Options& o) {
    std::vector<std::string> names;
    std::stringstream list(o.models);
    for (std::string m; std::getline(list, m, ',');)
        if (!m.empty()) names.push_back(m);
    if (names.empty()) throw UsageError("--model: no model named");
    const auto t0 = std::chrono::steady_clock::now();
    ngi::Device device = ngi::Device::open(o.device);
    const double open_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    nlohmann::json out = {{"device", device.info().name}, {"platform", device.info().platform_name},
                          {"cache_dir", ngi::program_cache_dir().string()}, {"open_device_ms", open_ms},
                          {"n", o.n}, {"display", o.display}, {"models", nlohmann::json::array()}};
    for (const std::string& name : names) {
        const std::string path = ngi::resolve_model(name);
        const auto t1 = std::chrono::steady_clock::now();
        ngi::Model model = ngi::Model::load(device, path);
        const double load_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count();
        const ngi::WarmUpReport r = ngi::warm_up(device, model, o.n, o.display);
        out["models"].push_back({{"model", name}, {"load_ms", load_ms}, {"programs_built", r.programs_built},
                                 {"programs_from_cache", r.programs_from_cache}, {"first_frame_ms", r.first_frame_ms},
                                 {"second_frame_ms", r.second_frame_ms}});
        if (!o.json)
            std::printf("%-28s load %.1f ms, warm-up frame %.1f ms (%d programs built, %d from the cache), "
                        "next frame %.1f ms\n", name.c_str(), load_ms, r.first_frame_ms, r.programs_built,
                        r.programs_from_cache, r.second_frame_ms);
    }
    if (o.json) std::printf("%s\n", out.dump(1).c_str());
    else std::printf("cache      %s (device %s, opened in %.1f ms)\n", out["cache_dir"].get<std::string>().c_str(),
                     device.info().name.c_str(), open_ms);
    return kExitOk;
}

}  // namespace

Run add_warmup(CLI::App& app) {
    auto o = std::make_shared<Options>();
    CLI::App* cmd = add_command(
        app, "warmup", "build every OpenCL program a model's frames need into the program cache (fast later starts)",
        "Runs each model once on a synthetic frame at face size N (and through a display view of --display pixels) so "
        "that the programs and work-group sizes a real frame uses are compiled and cached: $NGI_CACHE_DIR (else "
        "$XDG_CACHE_HOME/ngi or ~/.cache/ngi) and, on PoCL, $POCL_CACHE_DIR. Run it at install time, or ship the "
        "folder built on the same device and driver. A cache folder that cannot be written is an error (exit 1).");
    add_path(*cmd, "--model", o->models, "M[,M...]", "frame rungs: shipped model names or .safetensors files", false)
        ->capture_default_str();
    add_integer(*cmd, "--n", o->n, 2, 2048, "N", "face size the application runs");
    add_integer(*cmd, "--display", o->display, 0, 16384, "S", "also a display view of S x S pixels (0: none)");
    add_device(*cmd, o->device);
    add_switch(*cmd, "--json", o->json, "print one JSON object instead of text");
    return [o] { return run(*o); };
}

}  // namespace ngi_cli
