#include "runtime/programs.hpp"

#include "ngi/error.hpp"
#include "runtime/embedded_kernels.hpp"

namespace ngi::detail {

const std::vector<ProgramSources>& programs() {
    static const std::vector<ProgramSources> table = {
        // Ops (host/src/ops): the activations first where an op applies them.
        {"gemm", {"activation", "gemm"}},
        {"im2col", {"activation", "im2col"}},
        {"col2im", {"activation", "col2im"}},
        {"norm", {"activation", "norm"}},
        {"elementwise", {"activation", "elementwise"}},
        {"mlp", {"activation", "mlp"}},
        {"set_pool", {"set_pool"}},
        {"max_pool", {"max_pool"}},
        {"pad2d", {"pad2d"}},
        {"resize", {"resize"}},
        {"sh", {"sh_basis", "sh"}},
        {"probe_shade", {"sh_basis", "probe_shade"}},
        {"voxel_ltf", {"luminance", "voxel_ltf"}},
        {"jbu", {"jbu"}},
        {"jbu_vec", {"jbu", "jbu_vec"}},
        {"gather_image", {"gather_image"}},
        // Pipelines (host/src/pipeline).
        {"globalview", {"globalview"}},
        {"gbuffer", {"gbuffer"}},
        {"compose", {"tonemap", "compose"}},
        {"metrics", {"metrics"}},
        {"neural_gi", {"neural_gi"}},
        {"ssgi", {"ssgi"}},
        {"display", {"tonemap", "display"}},
        {"ao", {"ao"}},
        // Renderer (host/src/render): every tracing program is the scene (geometry, BVH, grid DDA) and its kernels;
        // only those that trace paths add the lighting (with the sunlit-patch weights every lit frame needs), its
        // random numbers and luminance. Kernels used together stay in one program: every PoCL program build costs
        // about 0.17 s of CPU whatever its size, more than a program's unused small kernels add.
        {"pathtrace", {"rng", "luminance", "geometry", "bvh", "scene", "lighting", "patch_weights", "pathtrace"}},
        {"ao_geometry", {"rng", "geometry", "bvh", "scene", "render_ao", "render_geometry"}},
        {"voxel_field",
         {"rng", "luminance", "sh_basis", "geometry", "bvh", "scene", "lighting", "patch_weights", "voxel_field"}},
        {"voxel_visibility", {"geometry", "voxel_visibility"}},
        {"voxel_compact", {"geometry", "voxel_compact"}},
        {"bvh", {"geometry", "bvh"}},
        // Runtime (host/src/runtime): driver probes and kernel-side transfers.
        {"probe", {"probe"}},
        {"transfer", {"transfer"}},
    };
    return table;
}

const ProgramSources& program_sources(std::string_view name) {
    for (const ProgramSources& p : programs())
        if (p.name == name) return p;
    throw Error("build kernels: no program '" + std::string(name) + "' in host/src/runtime/programs.cpp");
}

namespace {

const EmbeddedKernel& embedded(std::string_view file) {
    for (std::size_t i = 0; i < kEmbeddedKernelCount; ++i)
        if (file == kEmbeddedKernels[i].name) return kEmbeddedKernels[i];
    throw Error("load kernel source: no embedded kernel file '" + std::string(file) + ".cl'");
}

void append_file(std::string& source, std::string_view file) {
    source += "#line 1 \"" + std::string(file) + ".cl\"\n";
    source += embedded(file).source;
    source += '\n';  // a file need not end with a newline
}

}  // namespace

std::string program_source(std::string_view name) {
    const ProgramSources& p = program_sources(name);
    std::string source;
    append_file(source, "common");
    for (std::string_view f : p.files) append_file(source, f);
    return source;
}

}  // namespace ngi::detail
