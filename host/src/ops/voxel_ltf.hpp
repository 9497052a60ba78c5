// Seed 004's light-transition function over a scene's occupied surface voxels (kernels/voxel_ltf.cl), matrix-free
// (one work-item per receiver sums over the senders; no V x V matrix), Jacobi iteration with ping-pong buffers.
// Two variants: the honest physical baseline (radiosity with visibility) and the paper's Eq. 23-30 as written,
// normalized so energy cannot grow. Maths, conventions and deviations from the paper: docs/VOXEL_LTF.md.
// Plain device buffers in, so the op does not depend on how the per-voxel field is built.
#pragma once
#include <map>
#include <tuple>
#include <vector>

#include "runtime/context.hpp"

namespace ngi::detail {

// Distance floor of every 1 / r^2 (metres): the point-to-area form factor of adjacent voxels is already poor and it
// diverges as r -> 0. Reaches kernels/voxel_ltf.cl as the build option LTF_R_MIN.
constexpr float kLtfRMin = 0.5f;
// Bounces accepted by run(): 0 returns d; every bounce is O(V^2), and the seed reports t = 1..8.
constexpr int kLtfMaxBounces = 64;
// Voxels accepted by run(): 2^20. One bounce is V^2 pair terms (10^12 here: hours on a CPU; a 48^3 Cornell box
// has ~10^4 surface voxels), indices stay far inside int32, and the visibility mask of V voxels is V^2 / 8 bytes
// (a caller's buffer, checked against its size).
constexpr int kLtfMaxVoxels = 1 << 20;

enum class LtfVariant : int {
    Physical = 0,   // L^{t+1} = d + K L^t, K_ij = V_ij G_ij rho_j: both cosines, j's exposed area, / (pi r^2)
    AsWritten = 1,  // E^{t+1} = T (rho (.) E^t), T_ij = |n_i . w_ij| r_ij^-2 / Z_j; output E^0 + ... + E^t
};

// Kernel shape of the gather; every shape sums the senders of a receiver in the same order.
//   Plain:  one receiver per work-item, senders streamed from global memory.
//   Tiled:  as Plain, but a work-group stages LTF_LOCAL senders at a time in __local memory: the GPU shape (one
//           global read per sender per work-group instead of per work-item).
//   Vector: kLtfVectorLanes receivers per work-item as the lanes of a float vector: the CPU shape. PoCL
//           vectorizes across work-items only loops without inner loops, so Plain runs scalar on it.
//   Auto:   Tiled on GPUs, Vector on CPUs (docs/VOXEL_LTF.md has the measurements).
enum class LtfKernelShape : int { Auto = 0, Plain = 1, Tiled = 2, Vector = 3 };
constexpr int kLtfVectorLanes = 8;

// The per-voxel inputs: V voxels, float4 per voxel (w unused) unless stated. Buffers are read only.
struct LtfInputs {
    int voxels = 0;
    cl_mem position = nullptr;  // voxel centre, metres
    cl_mem normal = nullptr;    // unit normal
    cl_mem albedo = nullptr;    // rho, linear rgb
    cl_mem direct = nullptr;    // d: direct lighting (irradiance / pi), rgb
    cl_mem exposed = nullptr;   // uint32 per voxel: bit f = face f exposed (0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z)
};

class VoxelLtf {
public:
    explicit VoxelLtf(Context& ctx, LtfKernelShape shape = LtfKernelShape::Auto);

    // out [V] float4 = the lighting after `bounces` bounces (0: d). visibility: null (every pair visible) or
    // uint32 [V][ceil(V / 32)], bit j % 32 of word j / 32 of row i = receiver i sees sender j; only Physical
    // reads it (the paper's LTF has no shadow term: a mask with AsWritten is an InputError). energy (optional):
    // bounces + 1 values, per iterate the sum over voxels of the luminance of E^t (AsWritten) or of the bounce
    // increment L^t - L^{t-1} (Physical; L^{-1} = 0), costing one download at the end.
    // Everything else stays on the device's queue (no host transfer, no wait) when energy is null.
    void run(Context& ctx, const LtfInputs& in, int bounces, LtfVariant variant, cl_mem visibility, cl_mem out,
             std::vector<double>* energy = nullptr);

    LtfKernelShape shape() const { return shape_; }
    // Caps the senders one launch sums (tests: any split must give bit-identical results). 0 = no cap beyond the
    // device's loop limit.
    void set_max_senders_per_launch(int n) { max_senders_ = n; }

private:
    Kernel& gather(Context& ctx, LtfVariant variant, bool vis);
    int lanes() const;  // receivers per work-item of the gather
    // Senders per launch of the gather (or of the normalizer: plain, no mask) under the device's loop limit.
    int senders_per_launch(Context& ctx, bool tiled, int lanes, bool vis) const;
    void ensure_scratch(Context& ctx, int voxels);

    LtfKernelShape shape_;
    int max_senders_ = 0;
    Kernel pack_, normalizer_, senders_, accumulate_, energy_;
    std::map<std::tuple<int, int>, Kernel> gathers_;  // (variant, visibility) -> gather of this op's shape
    int scratch_voxels_ = 0;
    Buffer geometry_, mid_, half_, sender_, z_, ping_, pong_, partial_;
};

}  // namespace ngi::detail
