// The table of OpenCL sources compiled into the library (generated from kernels/*.cl at build time).
#pragma once
#include <cstddef>

namespace ngi::detail {

struct EmbeddedKernel {
    const char* name;    // file name without extension, e.g. "gemm"
    const char* source;  // NUL-terminated OpenCL C source
    std::size_t size;
};

extern const EmbeddedKernel kEmbeddedKernels[];
extern const std::size_t kEmbeddedKernelCount;

}  // namespace ngi::detail
