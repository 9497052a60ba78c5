// The C API over the C++ API: exceptions become status codes plus a thread-local message.
#include "ngi.h"

#include <cstring>
#include <new>
#include <string>

#include "ngi/device.hpp"
#include "ngi/error.hpp"
#include "ngi/model.hpp"

struct ngi_device {
    ngi::Device device;
};
struct ngi_model {
    ngi::Model model;
    int sanitized_inputs = 0;  // of the last successful run
};

namespace {

thread_local std::string g_last_error;
thread_local int g_last_cl_error = 0;

template <class F>
ngi_status guarded(F&& f) {
    try {
        f();
        return NGI_OK;
    } catch (const ngi::ClError& e) {
        g_last_error = e.what();
        g_last_cl_error = e.code();
        return NGI_ERROR_OPENCL;
    } catch (const ngi::InputError& e) {
        g_last_error = e.what();
        return NGI_ERROR_INPUT;
    } catch (const std::bad_alloc&) {
        g_last_error = "out of host memory";
        return NGI_ERROR_INTERNAL;
    } catch (const std::exception& e) {
        g_last_error = e.what();
        return NGI_ERROR_INTERNAL;
    }
}

ngi_status invalid(const char* what) {
    g_last_error = what;
    return NGI_ERROR_INVALID_ARGUMENT;
}

}  // namespace

extern "C" {

const char* ngi_last_error(void) { return g_last_error.c_str(); }
int ngi_last_cl_error(void) { return g_last_cl_error; }

ngi_status ngi_device_open(const char* spec, ngi_device** out) {
    if (!out) return invalid("ngi_device_open: out is NULL");
    *out = nullptr;
    return guarded([&] { *out = new ngi_device{ngi::Device::open(spec ? spec : "")}; });
}

const char* ngi_device_name(const ngi_device* device) { return device ? device->device.info().name.c_str() : ""; }

void ngi_device_release(ngi_device* device) { delete device; }

ngi_status ngi_model_load(ngi_device* device, const char* path, ngi_model** out) {
    if (!device || !path || !out) return invalid("ngi_model_load: device, path and out must not be NULL");
    *out = nullptr;
    return guarded([&] { *out = new ngi_model{ngi::Model::load(device->device, path)}; });
}

ngi_status ngi_model_channels(const ngi_model* model, int* input_nc, int* output_nc, int* num_downs) {
    if (!model) return invalid("ngi_model_channels: model is NULL");
    const auto& c = model->model.config();
    if (input_nc) *input_nc = c.input_nc;
    if (output_nc) *output_nc = c.output_nc;
    if (num_downs) *num_downs = c.num_downs;
    return NGI_OK;
}

ngi_status ngi_model_run(ngi_model* model, const float* input, int height, int width, float* output) {
    if (!model || !input || !output) return invalid("ngi_model_run: model, input and output must not be NULL");
    if (height < 1 || width < 1) return invalid("ngi_model_run: height and width must be positive");
    return guarded([&] {
        const auto& c = model->model.config();
        ngi::Tensor in({1, c.input_nc, height, width});
        std::memcpy(in.data.data(), input, in.size() * sizeof(float));
        ngi::RunInfo info;
        const ngi::Tensor y = model->model.run(in, &info);
        std::memcpy(output, y.data.data(), y.size() * sizeof(float));
        model->sanitized_inputs = info.sanitized_inputs;
    });
}

ngi_status ngi_model_sanitized_inputs(const ngi_model* model, int* count) {
    if (!model || !count) return invalid("ngi_model_sanitized_inputs: model and count must not be NULL");
    *count = model->sanitized_inputs;
    return NGI_OK;
}

void ngi_model_release(ngi_model* model) { delete model; }

}  // extern "C"
