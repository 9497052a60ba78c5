// Library-internal access to a Model's device path with raw OpenCL buffers (the pipeline feeds the model from its
// own scratch buffers without wrapping them in DeviceBuffers).
#pragma once
#include <CL/cl.h>

#include <cstddef>

#include "ngi/model.hpp"

namespace ngi::detail {

struct ModelAccess {
    // Model::enqueue without the public checks: the caller guarantees the sizes and the context.
    static void enqueue(Model& model, cl_mem in, std::size_t in_offset, cl_mem out, std::size_t out_offset,
                        int height, int width);
    static const Device& device(const Model& model);
};

}  // namespace ngi::detail
