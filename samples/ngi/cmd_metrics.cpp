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

// ngi metrics A B [--range R] [--device D]: prints {"mse": ..., "psnr": ..., "ssim": ...} as one JSON object
// (ngi::to_json). JSON has no infinity or NaN: a psnr or ssim that is not a finite number is printed as null with a
// "psnr_note" / "ssim_note" saying why (identical images: psnr +infinity; --range 0: both undefined; images
// smaller than 11x11: no SSIM).
int cmd_metrics(int argc, char** argv) {
    Args args(argc, argv, 2, {}, {"range", "device"});
    if (args.positional().size() != 2) throw UsageError("expected two image files (.exr, .png or .npy)");
    double range = 1.0;
    try {
        range = args.real("range", 1.0, 0.0, std::numeric_limits<double>::max());
    } catch (const UsageError&) {
        throw UsageError("--range needs a finite number >= 0, got '" + args.get("range") + "'");
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
    std::printf("%s\n", ngi::to_json(m).c_str());
    return 0;
}

}  // namespace ngi_cli
