#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>

#include "commands.hpp"
#include "ngi/error.hpp"
#include "ngi/image_io.hpp"
#include "ngi/metrics.hpp"

namespace ngi_cli {

// ngi metrics A B [--range R] [--device D]: prints {"mse": ..., "psnr": ..., "ssim": ...} as one JSON object.
// JSON has no infinity: for identical images (mse 0) psnr is printed as null.
int cmd_metrics(int argc, char** argv) {
    Args args(argc, argv, 2, {}, {"range", "device"});
    if (args.positional().size() != 2) throw UsageError("expected two image files (.exr, .png or .npy)");
    double range = 1.0;
    try {
        range = args.real("range", 1.0, std::numeric_limits<double>::min(), std::numeric_limits<double>::max());
    } catch (const UsageError&) {
        throw UsageError("--range needs a finite number > 0, got '" + args.get("range") + "'");
    }
    const ngi::Image a = ngi::read_image(args.positional()[0]);
    const ngi::Image b = ngi::read_image(args.positional()[1]);
    auto dims = [](const ngi::Image& i) {
        return std::to_string(i.width) + "x" + std::to_string(i.height) + "x" + std::to_string(i.channels);
    };
    if (a.width != b.width || a.height != b.height || a.channels != b.channels)
        throw ngi::InputError(args.positional()[0] + " is " + dims(a) + " but " + args.positional()[1] + " is " +
                              dims(b) + " (width x height x channels); the images must match");
    ngi::Device device = ngi::Device::open(args.get("device"));
    const ngi::ImageMetrics m = ngi::compare_images(device, a, b, range);
    char psnr[32] = "null";  // JSON has no infinity: null stands for the +inf PSNR of identical images
    if (std::isfinite(m.psnr)) std::snprintf(psnr, sizeof psnr, "%.17g", m.psnr);
    std::printf("{\"mse\": %.17g, \"psnr\": %s, \"ssim\": %.17g}\n", m.mse, psnr, m.ssim);
    return 0;
}

}  // namespace ngi_cli
