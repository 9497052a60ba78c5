// ngi dataset: render a whole dataset from a JSON config, resumably, with a progress bar on stderr.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include "commands.hpp"
#include "ngi/dataset.hpp"

namespace ngi_cli {
namespace {

std::string hms(double s) {
    const long t = long(s + 0.5);
    char b[32];
    std::snprintf(b, sizeof b, "%ld:%02ld:%02ld", t / 3600, t / 60 % 60, t % 60);
    return b;
}

struct Options {
    std::string config_path, out, device;
};

int run(const Options& o) {
    const std::string &config_path = o.config_path, &out = o.out;
    const ngi::DatasetConfig config = ngi::DatasetConfig::load(config_path);
    ngi::Device device = ngi::Device::open(o.device);
    const bool tty = isatty(STDERR_FILENO);
    auto last = std::chrono::steady_clock::now() - std::chrono::hours(1);
    std::fprintf(stderr, "dataset %s: %zu train + %zu test scenes, N = %d, %d spp reference, device %s\n",
                 config_path.c_str(), config.train.size(), config.test.size(), config.render.n,
                 config.render.reference_spp, device.info().name.c_str());
    ngi::render_dataset(device, config, out, [&](const ngi::DatasetProgress& p) {
        const auto now = std::chrono::steady_clock::now();
        const bool finished = p.frames_done == p.frames_total;
        // On a terminal redraw in place; in a log, one line every 10 s.
        if (!finished && now - last < std::chrono::milliseconds(tty ? 200 : 10000)) return;
        last = now;
        const double per = p.frames_rendered ? p.rendered_seconds / p.frames_rendered : 0.0;
        const double eta = per * (p.frames_total - p.frames_done);
        const int width = 30, filled = p.frames_total ? width * p.frames_done / p.frames_total : width;
        std::fprintf(stderr, "%s[%s%s] %d/%d frames (%d skipped)  %.2f s/frame  ETA %s  rel.err %.3f  %s%s",
                     tty ? "\r" : "", std::string(std::size_t(filled), '#').c_str(),
                     std::string(std::size_t(width - filled), '.').c_str(), p.frames_done, p.frames_total,
                     p.frames_skipped, per, hms(eta).c_str(), p.last_rel_stderr, p.scene.c_str(),
                     tty ? "\x1b[K" : "\n");
        if (finished && tty) std::fputc('\n', stderr);
    });
    std::printf("dataset written to %s\n", out.c_str());
    return 0;
}

}  // namespace

Run add_dataset(CLI::App& app) {
    auto o = std::make_shared<Options>();
    CLI::App* cmd = add_command(app, "dataset", "render a train/test dataset from a JSON config (see configs/)",
                                "Resumable: finished frames are kept. Progress with an ETA on stderr.");
    add_path(*cmd, "--config", o->config_path, "FILE.json", "the dataset config", true);
    add_path(*cmd, "--out", o->out, "DIR", "the dataset folder", true);
    add_device(*cmd, o->device);
    return [o] { return run(*o); };
}

}  // namespace ngi_cli
