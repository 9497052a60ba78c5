// Library-internal access to a Model's device path with raw OpenCL buffers (the pipeline feeds the model from its
// own scratch buffers without wrapping them in DeviceBuffers), and to the metadata the public ModelConfig does not
// hold (an AO network's "ao" object).
#pragma once
#include <CL/cl.h>

#include <cstddef>
#include <string>

#include "models/ao_metadata.hpp"
#include "ngi/model.hpp"

namespace ngi::detail {

struct ModelAccess {
    // Model::enqueue without the public checks: the caller guarantees the sizes and the context.
    static void enqueue(Model& model, cl_mem in, std::size_t in_offset, cl_mem out, std::size_t out_offset,
                        int height, int width);
    static const Device& device(const Model& model);
    // The "ao" object of an "mlp" model's metadata, from the metadata parsed at load (parse_ao_metadata: InputError
    // starting with `what` when it is missing or a field is out of range).
    static AoMetadata ao(const Model& model, const std::string& what);
};

}  // namespace ngi::detail
