// Writes ngi/_constants.py: the values the Python side shares with the C++ library and its kernels, printed from
// their one C++ definition, so no Python file carries a copy. Run by the build (bindings/python/CMakeLists.txt) in
// every configuration, sanitizer builds included: the pure-Python modules (ngi.neural_gi, ngi.scoring, the training
// code) need these without the native module.
#include <charconv>
#include <cstdio>
#include <fstream>
#include <string>

#include "models/config_fields.hpp"
#include "models/graph_model.hpp"
#include "models/voxel_sh_model.hpp"
#include "ops/luminance.hpp"
#include "ngi/render.hpp"
#include "ops/op_types.hpp"
#include "pipeline/frame_planes.hpp"
#include "pipeline/neural_gi_inputs.hpp"
#include "pipeline/pipeline_impl.hpp"

namespace {

// The shortest decimal that reads back as v (in v's own precision), as a Python float literal.
template <class T>
std::string py_float(T v) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    std::string s(buf, r.ptr);
    if (s.find_first_of(".e") == std::string::npos) s += ".0";
    return s;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s OUT.py\n", argv[0]);
        return 2;
    }
    using namespace ngi;
    std::string s =
        "\"\"\"Values the Python side shares with ngi's C++ library and kernels. Generated at build time by\n"
        "bindings/python/constants/gen_constants.cpp from their C++ definitions: do not edit.\"\"\"\n\n";
    s += "# host/src/pipeline/neural_gi_inputs.hpp kNeuralGiRadianceMax: the bound of seed 002's radiances.\n";
    s += "NEURAL_GI_RADIANCE_MAX = " + py_float(detail::kNeuralGiRadianceMax) + "\n";
    s += "# host/src/ops/op_types.hpp kActExpMax: the \"exp\" activation is exp(min(x, ACT_EXP_MAX)).\n";
    s += "ACT_EXP_MAX = " + py_float(kActExpMax) + "\n";
    s += "# host/src/base/surface_depth.hpp kMaxSurfaceDepth: depth (metres) beyond which a texel is no surface.\n";
    s += "MAX_SURFACE_DEPTH = " + py_float(ngi::detail::kMaxSurfaceDepth) + "\n";
    s += "# host/src/models/voxel_sh_model.hpp kVoxelShInputBound: the voxel_sh input guard's bound.\n";
    s += "VOXEL_SH_INPUT_BOUND = " + py_float(detail::kVoxelShInputBound) + "\n";
    s += "# host/src/pipeline/pipeline_impl.hpp kLightMax: the largest lightmap value the decoding produces.\n";
    s += "LIGHT_MAX = " + py_float(detail::kLightMax) + "\n";
    s += "# host/src/ops/luminance.hpp kRec709Luma: Rec. 709 luminance weights (R, G, B).\n";
    s += "REC709_LUMA = (" + py_float(detail::kRec709Luma[0]) + ", " + py_float(detail::kRec709Luma[1]) + ", " +
         py_float(detail::kRec709Luma[2]) + ")\n";
    s += "# host/include/ngi/render.hpp kEngineFeatureSpp: direct-light samples per pixel of an engine's (converged) input.\n";
    s += "ENGINE_FEATURE_SPP = " + std::to_string(kEngineFeatureSpp) + "\n";
    s += "# host/src/models/graph_model.hpp, config_fields.hpp: the graph loader's limits (ngi.convert refuses beyond them).\n";
    s += "GRAPH_MAX_NODES = " + std::to_string(detail::kMaxGraphNodes) + "\n";
    s += "GRAPH_MAX_NAME_BYTES = " + std::to_string(detail::kMaxGraphNameLength) + "\n";
    s += "GRAPH_MAX_NODE_INPUTS = " + std::to_string(detail::kMaxGraphNodeInputs) + "\n";
    s += "GRAPH_MAX_KERNEL = " + std::to_string(detail::kMaxGraphKernel) + "\n";
    s += "GRAPH_MAX_STRIDE = " + std::to_string(detail::kMaxGraphStride) + "\n";
    s += "GRAPH_MAX_PAD = " + std::to_string(detail::kMaxGraphPad) + "\n";
    s += "GRAPH_MAX_CHANNELS = " + std::to_string(detail::kMaxChannels) + "\n";
    const std::string tmp = std::string(argv[1]) + ".tmp";
    {
        std::ofstream f(tmp, std::ios::binary);
        f << s;
        if (!f.flush()) {
            std::fprintf(stderr, "gen_constants: cannot write %s\n", tmp.c_str());
            return 1;
        }
    }
    if (std::rename(tmp.c_str(), argv[1]) != 0) {
        std::fprintf(stderr, "gen_constants: cannot rename %s to %s\n", tmp.c_str(), argv[1]);
        return 1;
    }
    return 0;
}
