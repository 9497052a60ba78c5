#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <string>

#include "commands.hpp"
#include "ngi/error.hpp"
#include "ngi/image_io.hpp"
#include "ngi/metrics.hpp"

namespace ngi_cli {

// ngi metrics A B [--range R] [--device D]: prints {"mse": ..., "psnr": ..., "ssim": ...} as one JSON object
// (ngi::to_json). JSON has no infinity or NaN: a psnr or ssim that is not a finite number is printed as null with a
// "psnr_note" / "ssim_note" saying why (identical images: psnr +infinity; --range 0: both undefined; images
// smaller than 11x11: no SSIM).
namespace {

struct Options {
    std::string a, b, device;
    double range = 1.0;
};

int run(const Options& o) {
    // The library's bound on a positive range (compare_images), as a usage error before reading anything.
    if (o.range > 0.0 && o.range < 1e-15) {
        char got[32];
        std::snprintf(got, sizeof got, "%g", o.range);
        throw UsageError(std::string("--range needs 0 or a finite number in 1e-15..1e15, got '") + got + "'");
    }
    const ngi::Image a = ngi::read_image(o.a);
    const ngi::Image b = ngi::read_image(o.b);
    auto dims = [](const ngi::Image& i) {
        return std::to_string(i.width) + "x" + std::to_string(i.height) + "x" + std::to_string(i.channels);
    };
    if (a.width != b.width || a.height != b.height || a.channels != b.channels)
        throw ngi::InputError(o.a + " is " + dims(a) + " but " + o.b + " is " + dims(b) +
                              " (width x height x channels); the images must match");
    ngi::Device device = ngi::Device::open(o.device);
    const ngi::ImageMetrics m = ngi::compare_images(device, a, b, o.range);
    std::printf("%s\n", ngi::to_json(m).c_str());
    return 0;
}

}  // namespace

Run add_metrics(CLI::App& app) {
    auto o = std::make_shared<Options>();
    CLI::App* cmd = add_command(app, "metrics", "MSE, PSNR and SSIM of two images (.exr/.png/.npy) as JSON",
                                "psnr is null for identical images, psnr and ssim are null for --range 0, ssim is null "
                                "for images smaller than 11x11; a note says why.");
    cmd->add_option("A", o->a, "the first image (.exr, .png or .npy)")->required();
    cmd->add_option("B", o->b, "the second image, of the same size and channel count")->required();
    add_real(*cmd, "--range", o->range, 0.0, 1e15, "R", "the data range (0, or 1e-15..1e15)");
    add_device(*cmd, o->device);
    return [o] { return run(*o); };
}

}  // namespace ngi_cli
