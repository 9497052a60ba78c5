// Probe shading (kernels/probe_shade.cl): lights the visible surfaces of one camera face from a per-voxel field,
// the SH-27 irradiance of seed 004's voxels or any per-voxel lighting (the LTF's, the path-traced ground truth).
// Each pixel's world point comes from the face's planar depth; the block behind its face is looked up in a dense
// index grid. Conventions and why: docs/VOXEL_LTF.md ("Probe shading").
#pragma once
#include <array>
#include <string>

#include "base/surface_depth.hpp"
#include "runtime/context.hpp"
#include "runtime/kernel_defines.hpp"

namespace ngi::detail {

// Every constant below reaches kernels/probe_shade.cl as a build option (probe_shade_defines()).
// Offset (metres) of the 26 fallback lookups around the block behind a face.
constexpr float kProbeNeighbourStep = 0.25f;
// Face sizes accepted (n x n pixels).
constexpr int kProbeMaxFace = 16384;

enum class ProbeField : int {
    Sh = 0,        // [V][3][9] SH coefficients of incident radiance: lighting = max(0, sum_k A_l c_k Y_k(n)) / pi
    PerVoxel = 1,  // [V] float4 lighting (w unused)
};

// Slots of the miss counters (uint32 [kProbeCounters]): ProbeShadeCounts::no_voxel, ::non_finite.
constexpr int kProbeCountNoVoxel = 0, kProbeCountNonFinite = 1, kProbeCounters = 2;

// The lookups of a surface pixel, in the order they are tried: the cell behind the surface first, then its 26
// neighbours at kProbeNeighbourStep: the 6 along the axes (one pair along the normal's axis), the 12 edge and the
// 8 corner offsets, each group in (x, y, z) lexicographic order of {-1, 0, 1}. Nearest first, so the first voxel
// found is the likeliest one.
constexpr std::array<std::array<int, 3>, 27> probe_neighbour_offsets() {
    std::array<std::array<int, 3>, 27> o{};
    int k = 0;
    for (int nonzero = 0; nonzero <= 3; ++nonzero)
        for (int a = -1; a <= 1; ++a)
            for (int b = -1; b <= 1; ++b)
                for (int c = -1; c <= 1; ++c)
                    if ((a != 0) + (b != 0) + (c != 0) == nonzero) o[std::size_t(k++)] = {a, b, c};
    return o;
}

// The build options of kernels/probe_shade.cl.
inline std::string probe_shade_defines() {
    std::array<int, 81> flat{};
    const auto o = probe_neighbour_offsets();
    for (std::size_t k = 0; k < o.size(); ++k)
        for (std::size_t a = 0; a < 3; ++a) flat[3 * k + a] = o[k][a];
    return join_defines({define("PROBE_MAX_DEPTH", kMaxSurfaceDepth), define("PROBE_NEIGHBOUR_STEP", kProbeNeighbourStep),
                         define_list("PROBE_NEIGHBOURS", flat), define("FIELD_SH", int(ProbeField::Sh)),
                         define("FIELD_PER_VOXEL", int(ProbeField::PerVoxel)), define("COUNT_NO_VOXEL", kProbeCountNoVoxel),
                         define("COUNT_NON_FINITE", kProbeCountNonFinite)});
}

// One face of the camera cluster, world space: pixel (col, row) looks along normalize(look + u right + v up),
// u = 2 (col + 0.5) / n - 1, v = 1 - 2 (row + 0.5) / n (docs/CONVENTIONS.md sections 1-3).
struct ProbeCamera {
    float centre[3] = {0, 0, 0};
    float look[3] = {0, 0, -1};
    float right[3] = {1, 0, 0};
    float up[3] = {0, 1, 0};
};

struct ProbeShadeInputs {
    int n = 0;                 // face size
    cl_mem depth = nullptr;    // float [n*n]: planar depth along look; beyond kMaxSurfaceDepth = no surface
    cl_mem normal = nullptr;   // float [3][n*n]: the visible face's unit normal; zero for sky
    ProbeCamera camera;
    int grid[3] = {0, 0, 0};   // X, Y, Z blocks; block (x, y, z) covers [x, x+1) x [y, y+1) x [z, z+1) metres
    cl_mem index_of = nullptr; // int32 [X*Y*Z]: voxel index of block x + X (y + Y z), or -1
    int voxels = 0;            // V: entries of index_of outside [0, V) count as empty
    ProbeField mode = ProbeField::Sh;
    cl_mem field = nullptr;    // [V][3][9] (Sh) or float4 [V] (PerVoxel); may be null when V = 0
};

// Pixels left at lighting 0 other than sky: a surface whose block (and its 26 neighbours at 0.25 m) holds no voxel,
// or whose normal is zero; and pixels with NaN/Inf depth or normal (shaded as sky).
struct ProbeShadeCounts {
    long no_voxel = 0;
    long non_finite = 0;
    long total() const { return no_voxel + non_finite; }
};

class ProbeShade {
public:
    explicit ProbeShade(Context& ctx);
    // out: float [3][n*n] (planar). Returns counts().total() after one 8-byte download when read_counts, else -1
    // with nothing transferred (the counters stay on the device: counts(), counts_buffer()).
    int enqueue(Context& ctx, const ProbeShadeInputs& in, cl_mem out, bool read_counts = true);
    // The counters of the last enqueue (one download).
    ProbeShadeCounts counts(Context& ctx) const;
    // uint32 [2]: no_voxel, non_finite of the last enqueue (the kernel's COUNT_NO_VOXEL, COUNT_NON_FINITE).
    cl_mem counts_buffer() const { return counts_.get(); }

private:
    Kernel kernel_;
    Buffer counts_;
};

}  // namespace ngi::detail
