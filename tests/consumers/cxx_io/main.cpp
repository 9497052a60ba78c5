// An out-of-tree consumer of ngi::io: writes an image as EXR (float) and PNG, reads both back and compares.
#include <cmath>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <ngi/image_io.hpp>
#include <string>

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s OUT_DIR\n", argv[0]);
        return 2;
    }
    try {
        const std::string dir = argv[1];
        ngi::Image img(7, 5, 3);
        for (std::size_t i = 0; i < img.data.size(); ++i) img.data[i] = float(i % 11) / 10.0f;
        ngi::write_exr(dir + "/io.exr", img, ngi::ExrPixelType::Float);
        ngi::write_png(dir + "/io.png", img);
        const ngi::Image exr = ngi::read_exr(dir + "/io.exr");
        const ngi::Image png = ngi::read_png(dir + "/io.png");
        if (exr.data != img.data) throw std::runtime_error("EXR round trip differs");
        if (png.width != 7 || png.height != 5 || png.channels != 3) throw std::runtime_error("PNG shape differs");
        for (std::size_t i = 0; i < img.data.size(); ++i)
            if (std::abs(png.data[i] - img.data[i]) > 0.5f / 255.0f + 1e-6f)
                throw std::runtime_error("PNG value " + std::to_string(i) + " differs by more than 8-bit rounding");
        std::fprintf(stderr, "c++ io consumer: 7x5x3 image through EXR (exact) and PNG (8-bit) and back\n");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "c++ io consumer: %s\n", e.what());
        return 1;
    }
    return 0;
}
