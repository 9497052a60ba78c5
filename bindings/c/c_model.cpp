// Model files of any family: loading (a path or a shipped model's name), what the model is, and running it on planar
// images or items from the host, or on device buffers.
#include "c_handles.hpp"

using namespace c_abi;

namespace {

// ngi_model_load and ngi_model_load_with_options, each reporting its own name: `path` is a file or a shipped model's
// name (ngi::resolve_model: $NGI_MODEL_PATH, the installed models, ...).
ngi_status load_model(const char* call, ngi_device* device, const char* path, ngi_bn_mode bn_mode, ngi_dropout dropout,
                      ngi_model** out) {
    return guarded(call, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        const ngi_device& d = live(device, "device");
        require(path, "path is NULL");
        ngi::ModelOptions options;
        switch (bn_mode) {
            case NGI_BN_FROM_FILE: break;
            case NGI_BN_RUNNING: options.bn_mode = "running"; break;
            case NGI_BN_PER_IMAGE: options.bn_mode = "per_image"; break;
            default: fail(NGI_ERROR_INVALID_ARGUMENT, "bn_mode " + std::to_string(int(bn_mode)) + " is not an ngi_bn_mode");
        }
        switch (dropout) {
            case NGI_DROPOUT_FROM_FILE: break;
            case NGI_DROPOUT_OFF: options.dropout = "off"; break;
            case NGI_DROPOUT_SEEDED: options.dropout = "seeded"; break;
            default: fail(NGI_ERROR_INVALID_ARGUMENT, "dropout " + std::to_string(int(dropout)) + " is not an ngi_dropout");
        }
        *out = track(std::make_unique<ngi_model>(ngi::Model::load(d.device, ngi::resolve_model(path), options)));
    });
}

}  // namespace

extern "C" {

ngi_status ngi_model_load_with_options(ngi_device* device, const char* path, ngi_bn_mode bn_mode, ngi_dropout dropout,
                                       ngi_model** out) {
    return load_model(__func__, device, path, bn_mode, dropout, out);
}

ngi_status ngi_model_load(ngi_device* device, const char* path, ngi_model** out) {
    return load_model(__func__, device, path, NGI_BN_FROM_FILE, NGI_DROPOUT_FROM_FILE, out);
}

ngi_status ngi_model_resolve(const char* name_or_path, char* buf, size_t size, size_t* needed) {
    return guarded(__func__, [&] {
        require(name_or_path, "name_or_path is NULL");
        copy_string(ngi::resolve_model(name_or_path), buf, size, needed);
    });
}

ngi_status ngi_model_channels(const ngi_model* model, int* input_nc, int* output_nc, int* num_downs) {
    return guarded(__func__, [&] {
        const auto& c = live(model, "model").model.config();
        if (input_nc) *input_nc = c.input_nc;
        if (output_nc) *output_nc = c.output_nc;
        if (num_downs) *num_downs = c.unet.num_downs;
    });
}

ngi_status ngi_model_output_mode(const ngi_model* model, ngi_output_mode* mode) {
    return guarded(__func__, [&] {
        const auto& c = live(model, "model").model.config();
        require(mode, "mode is NULL");
        // The loader admits exactly these three values (host/src/models/unet.cpp).
        *mode = c.output_mode == "indirect"        ? NGI_OUTPUT_INDIRECT
                : c.output_mode == "ssgi_residual" ? NGI_OUTPUT_SSGI_RESIDUAL
                                                   : NGI_OUTPUT_LIGHTMAP;
    });
}

ngi_status ngi_model_family(const ngi_model* model, ngi_family* family) {
    return guarded(__func__, [&] {
        const std::string& f = live(model, "model").model.config().family;
        require(family, "family is NULL");
        static const std::pair<const char*, ngi_family> kFamilies[] = {
            {"pix2pix_unet", NGI_FAMILY_PIX2PIX_UNET}, {"deepillumination", NGI_FAMILY_DEEPILLUMINATION},
            {"mlp", NGI_FAMILY_MLP}, {"voxel_sh", NGI_FAMILY_VOXEL_SH}, {"neural_gi", NGI_FAMILY_NEURAL_GI},
            {"graph", NGI_FAMILY_GRAPH}, {"ssgi", NGI_FAMILY_SSGI}};
        *family = NGI_FAMILY_OTHER;  // a family newer than this enum is still a model the C ABI loads and runs
        for (const auto& [name, value] : kFamilies)
            if (f == name) *family = value;
    });
}

ngi_status ngi_model_traits(const ngi_model* model, ngi_model_input* input, int* has_network, int* output_keeps_size) {
    return guarded(__func__, [&] {
        const auto& c = live(model, "model").model.config();
        if (input) *input = c.input == ngi::ModelInput::items ? NGI_INPUT_ITEMS : NGI_INPUT_IMAGE;
        if (has_network) *has_network = c.has_network ? 1 : 0;
        if (output_keeps_size) *output_keeps_size = c.output_keeps_size ? 1 : 0;
    });
}

ngi_status ngi_model_run(ngi_model* model, const float* input, size_t input_bytes, int height, int width,
                         float* output, size_t output_bytes) {
    return guarded(__func__, [&] {
        ngi_model& m = live(model, "model");
        require(input, "input is NULL");
        require(output, "output is NULL");
        const auto& c = m.model.config();
        const std::size_t in_need = image_bytes(c.input_nc, height, width);
        const std::size_t out_need = image_bytes(c.output_nc, height, width);
        require(input_bytes >= in_need, "input_bytes is " + std::to_string(input_bytes) + ", the model needs " +
                                            std::to_string(in_need) + " for " + std::to_string(c.input_nc) + "x" +
                                            std::to_string(height) + "x" + std::to_string(width) + " floats");
        require(output_bytes >= out_need, "output_bytes is " + std::to_string(output_bytes) + ", the model writes " +
                                              std::to_string(out_need));
        ngi::RunInfo info;
        // The output this call's caller sized, output_nc x height x width: a network that resamples (e.g. a graph
        // with a stride or a pool) writes another size, refused instead of read past or cut.
        auto check_output = [&](const ngi::Tensor& y) {
            if (y.data.size() * sizeof(float) != out_need)
                fail(NGI_ERROR_INPUT, "the model's output is " + ngi::shape_string(y.shape) + ", not " +
                                          std::to_string(c.output_nc) + "x" + std::to_string(height) + "x" +
                                          std::to_string(width) + ": its network resamples (run it from C++ or "
                                          "Python, which size the output from the network)");
        };
        if (c.input == ngi::ModelInput::items) {
            // Model::run takes items by item, [N][input_nc] -> [N][output_nc] (voxel_sh takes nothing else); this
            // call's layout is planar, as ngi_model_enqueue's: [input_nc][N] -> [output_nc][N].
            const std::size_t items = std::size_t(height) * std::size_t(width);
            require(items <= std::size_t(std::numeric_limits<int>::max()), "height x width is over 2^31 items");
            ngi::Tensor in({int(items), c.input_nc});
            for (std::size_t i = 0; i < items; ++i)
                for (int k = 0; k < c.input_nc; ++k) in.data[i * c.input_nc + k] = input[std::size_t(k) * items + i];
            const ngi::Tensor y = m.model.run(in, &info);
            check_output(y);
            for (std::size_t i = 0; i < items; ++i)
                for (int k = 0; k < c.output_nc; ++k) output[std::size_t(k) * items + i] = y.data[i * c.output_nc + k];
        } else {
            ngi::Tensor in({1, c.input_nc, height, width});
            std::memcpy(in.data.data(), input, in_need);
            const ngi::Tensor y = m.model.run(in, &info);
            check_output(y);
            std::memcpy(output, y.data.data(), out_need);
        }
        m.sanitized_inputs = info.sanitized_inputs;
        m.last_was_enqueue = false;
    });
}

ngi_status ngi_model_run_items(ngi_model* model, const float* input, size_t input_bytes, int count, float* output,
                               size_t output_bytes) {
    return guarded(__func__, [&] {
        ngi_model& m = live(model, "model");
        const auto& c = m.model.config();
        if (c.input != ngi::ModelInput::items)
            fail(NGI_ERROR_INPUT, "the model's family is " + c.family + ", which takes images (ngi_model_run); "
                                  "items are for per-item networks (ngi_model_traits: NGI_INPUT_ITEMS)");
        require(input, "input is NULL");
        require(output, "output is NULL");
        require(count > 0, "count must be positive, got " + std::to_string(count));
        const std::size_t in_need = image_bytes(c.input_nc, count, 1), out_need = image_bytes(c.output_nc, count, 1);
        require_bytes(input_bytes, in_need, "input_bytes", std::to_string(count) + " items of " +
                                                               std::to_string(c.input_nc) + " floats");
        require_bytes(output_bytes, out_need, "output_bytes", std::to_string(count) + " items of " +
                                                                  std::to_string(c.output_nc) + " floats");
        ngi::Tensor in({count, c.input_nc});
        std::memcpy(in.data.data(), input, in_need);
        ngi::RunInfo info;
        const ngi::Tensor y = m.model.run(in, &info);
        std::memcpy(output, y.data.data(), out_need);
        m.sanitized_inputs = info.sanitized_inputs;
        m.last_was_enqueue = false;
    });
}

ngi_status ngi_model_enqueue(ngi_model* model, ngi_buffer* input, ngi_buffer* output, int height, int width) {
    return guarded(__func__, [&] {
        ngi_model& m = live(model, "model");
        const ngi_buffer& in = live(input, "input");
        const ngi_buffer& out = live(output, "output");
        const auto& c = m.model.config();
        const std::string shape = std::to_string(height) + "x" + std::to_string(width);
        require_buffer(in, image_bytes(c.input_nc, height, width), "input",
                       std::to_string(c.input_nc) + "x" + shape + " floats");
        require_buffer(out, image_bytes(c.output_nc, height, width), "output",
                       std::to_string(c.output_nc) + "x" + shape + " floats");
        m.model.enqueue(in.buffer, out.buffer, height, width);
        m.last_was_enqueue = true;
    });
}

ngi_status ngi_model_sanitized_inputs(ngi_model* model, int* count) {
    return guarded(__func__, [&] {
        ngi_model& m = live(model, "model");
        require(count, "count is NULL");
        *count = m.last_was_enqueue ? m.model.sanitized_inputs() : m.sanitized_inputs;
    });
}

ngi_status ngi_model_retain(ngi_model* model) { return guarded(__func__, [&] { retain_handle(model, "model"); }); }
ngi_status ngi_model_release(ngi_model* model) { return guarded(__func__, [&] { release_handle(model, "model"); }); }

}  // extern "C"
