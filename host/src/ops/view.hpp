// A tensor as the ops see it: a buffer, an element offset and a shape. Views let the memory planner place
// tensors inside one arena and let a concat's inputs live side by side inside its output.
#pragma once
#include <CL/cl.h>

#include "ops/op_types.hpp"

namespace ngi::detail {

struct View {
    cl_mem mem = nullptr;
    std::size_t offset = 0;  // in floats
    Shape shape;
};

}  // namespace ngi::detail
