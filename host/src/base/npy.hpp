// The .npy decoder behind ngi::read_npy (ngi/tensor.hpp), in ngi_core with it: the file's bytes plus the path they
// came from (used only in error messages), so the fuzz target (fuzz/fuzz_npy.cpp) feeds bytes without the disk.
// Library-internal.
#pragma once
#include <string>

#include "ngi/tensor.hpp"

namespace ngi::detail {

Tensor decode_npy(const std::string& bytes, const std::string& path);

}  // namespace ngi::detail
