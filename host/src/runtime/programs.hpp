// The OpenCL programs ngi builds, declared in one table: each is an ordered list of kernels/*.cl files, compiled as
// one translation unit after kernels/common.cl (OpenCL C 1.2 cannot #include the library's embedded sources). A
// file comes after every file whose helpers it uses, and a program lists only what its kernels need: PoCL and
// llvmpipe compile time grows with the source. Library-internal.
#pragma once
#include <string>
#include <string_view>
#include <vector>

namespace ngi::detail {

struct ProgramSources {
    std::string_view name;                // what Context::kernel() takes, e.g. "pathtrace"
    std::vector<std::string_view> files;  // kernels/<file>.cl in build order; common.cl is always first, unlisted
};

// Every program (programs.cpp).
const std::vector<ProgramSources>& programs();

// The table's entry for `name`; throws Error naming it when there is none.
const ProgramSources& program_sources(std::string_view name);

// The source of a program: kernels/common.cl, then each of its files, each after a `#line 1 "<file>.cl"` so that
// build logs name the file and line. Everything a program is built from, so its cache key (Context::variant_key)
// changes with any of its files.
std::string program_source(std::string_view name);

}  // namespace ngi::detail
