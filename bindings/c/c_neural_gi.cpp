// Seed 002's Neural GI (ngi::NeuralGiRenderer): a frame with its camera position and area light -> indirect light
// and lighting.
#include <climits>

#include "c_handles.hpp"

using namespace c_abi;

extern "C" {

ngi_status ngi_neural_gi_new(ngi_device* device, ngi_neural_gi** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        *out = track(std::make_unique<ngi_neural_gi>(live(device, "device").device));
    });
}

ngi_status ngi_neural_gi_run(ngi_neural_gi* renderer, ngi_model* model, const ngi_frame* frame, int upsample,
                             float* indirect, size_t indirect_bytes, float* lighting, size_t lighting_bytes,
                             int* sanitized_inputs) {
    return guarded(__func__, [&] {
        ngi_neural_gi& r = live(renderer, "renderer");
        ngi_model& m = live(model, "model");
        const ngi::Frame& f = live(frame, "frame").frame;
        require(indirect || lighting, "indirect and lighting are both NULL: nothing to make");
        const std::size_t need = image_bytes(3, f.n, f.n);
        const std::string what = "a 3 x " + std::to_string(f.n) + " x " + std::to_string(f.n) + " image";
        if (indirect) require_bytes(indirect_bytes, need, "indirect_bytes", what);
        if (lighting) require_bytes(lighting_bytes, need, "lighting_bytes", what);
        require(upsample >= 1 && upsample <= 64, "upsample " + std::to_string(upsample) + " is not in 1..64");
        ngi::NeuralGiOptions options;
        options.upsample = upsample;
        const ngi::NeuralGiImages out = r.renderer.run(m.model, f, options);
        if (indirect) std::memcpy(indirect, out.indirect.data.data(), need);
        if (lighting) std::memcpy(lighting, out.lighting.data.data(), need);
        // Every value replaced on the way in: NaN/Inf in the frame's features and the model guard's replacements.
        if (sanitized_inputs)
            *sanitized_inputs = int(std::min<std::size_t>(std::size_t(out.sanitized_inputs) + out.nonfinite_features,
                                                          std::size_t(INT_MAX)));
        m.sanitized_inputs = out.sanitized_inputs;
        m.last_was_enqueue = false;
    });
}

ngi_status ngi_neural_gi_retain(ngi_neural_gi* renderer) {
    return guarded(__func__, [&] { retain_handle(renderer, "renderer"); });
}
ngi_status ngi_neural_gi_release(ngi_neural_gi* renderer) {
    return guarded(__func__, [&] { release_handle(renderer, "renderer"); });
}

}  // extern "C"
