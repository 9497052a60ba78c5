// An out-of-tree consumer of ngi::core alone: opens a device, finds a shipped model by name (ngi::resolve_model:
// NGI_MODEL_PATH or the installed share/ngi/models), runs it on a small input and checks the output is finite.
// Prints the file the name resolved to on stdout (the caller checks it is the installed one).
#include <cmath>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>
#include <ngi/model.hpp>
#include <ngi/tensor.hpp>

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s MODEL_NAME\n", argv[0]);
        return 2;
    }
    try {
        const std::string file = ngi::resolve_model(argv[1]);
        ngi::Device device = ngi::Device::open();
        ngi::Model model = ngi::Model::load(device, file);
        const ngi::ModelConfig& c = model.config();
        const int side = 1 << c.unet.num_downs;
        ngi::Tensor x({1, c.input_nc, side, side});
        for (std::size_t i = 0; i < x.data.size(); ++i) x.data[i] = float(i % 13) / 13.0f * 2.0f - 1.0f;
        const ngi::Tensor y = model.run(x);
        for (float v : y.data)
            if (!std::isfinite(v)) throw std::runtime_error("output is not finite");
        std::fprintf(stderr, "c++ core consumer: model '%s' = %s: %s, %d -> %d channels at %dx%d, finite\n", argv[1],
                     file.c_str(), c.family.c_str(), c.input_nc, c.output_nc, side, side);
        std::printf("%s\n", file.c_str());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "c++ core consumer: %s\n", e.what());
        return 1;
    }
    return 0;
}
