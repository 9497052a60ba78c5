// The packed, register-tiled GEMM (kernels/gemm.cl) and its per-device parameters.
#pragma once
#include <string>
#include <vector>

#include "ops/op_types.hpp"
#include "runtime/context.hpp"

namespace ngi::detail {

// Kernel knobs; see kernels/gemm.cl. Chosen per device by gemm_params_for() (the tuning database), overridable with
// NGI_GEMM="MR,VW,NV,KU,L0,L1[,UNROLL[,KWG]]" for tuning, and checked on the device before use
// (ops/gemm_selfcheck.hpp).
struct GemmParams {
    int mr = 8, vw = 16, nv = 2, ku = 1;
    int local0 = 1, local1 = 1;  // work-group shape (tiles per work-group along m, n)
    int unroll = 1;              // 1: micro-kernel unrolled by the preprocessor; 0: loops + #pragma unroll
    // K chunk of the GPU-shaped kernel gemm_local (operands staged in local memory by work-groups of exactly
    // local0 x local1); 0: gemm_packed, operands read from global memory, work-group shape free.
    int kwg = 0;
    int nr() const { return vw * nv; }
    // Local memory gemm_local needs: (L0 MR + L1 NR) KWG floats (0 for gemm_packed).
    std::size_t local_mem_bytes() const {
        return std::size_t(local0 * mr + local1 * nr()) * std::size_t(kwg) * sizeof(float);
    }
    std::string defines() const;
    std::string to_string() const;  // "MR,VW,NV,KU,L0,L1,UNROLL", with ",KWG" appended when kwg > 0
};

// What kernels/gemm.cl is built with: the knobs (p.defines()) and the activation codes of its epilogue; the
// program is "gemm" (activation.cl, gemm.cl).
inline std::string gemm_kernel_defines(const GemmParams& p) { return p.defines() + " " + activation_defines(); }
// What kernels/im2col.cl is built with (the program "im2col"): the panel width NR.
inline std::string im2col_defines(int nr) { return "-DNR=" + std::to_string(nr) + " " + activation_defines(); }

// The device's knob set: $NGI_GEMM if set, else the tuning database's best match (ops/gemm_tuning.hpp).
GemmParams gemm_params_for(const DeviceInfo& info);
// "MR,VW,NV,KU,L0,L1[,UNROLL[,KWG]]" (UNROLL 1, KWG 0 when left out); throws InputError. The device-dependent
// limits of a KWG > 0 set (local memory, work-group size) are checked by Gemm's constructor.
GemmParams parse_gemm_params(const std::string& s);
bool operator==(const GemmParams& a, const GemmParams& b);

// K rounded up so every packed panel has whole unroll steps.
inline int padded_k(int k, const GemmParams& p) { return int(round_up(std::size_t(k), std::size_t(p.ku))); }

// Host-side packing of a row-major M x K matrix (ld = row stride) into Ap panels of MR rows (zero padded).
std::vector<float> pack_a(const float* a, int M, int K, int ld, const GemmParams& p);

// Host-side packing of a row-major K x N matrix (ld = row stride) into Bp panels of NR columns (zero padded), the
// layout im2col_packed writes on the device. For tests, the self-check and benchmarks.
std::vector<float> pack_b(const float* b, int K, int N, int ld, const GemmParams& p);

// Size in floats of a packed B for K x N.
inline std::size_t packed_b_floats(int K, int N, const GemmParams& p) {
    return round_up(std::size_t(N), std::size_t(p.nr())) * std::size_t(padded_k(K, p));
}

// Packs a row-major K x N matrix (at x_off) on the device into Bp panels at bp_off, the input activation applied
// on the way (pack_panels in kernels/im2col.cl): the B operand of a 1 x 1 convolution or a dense layer.
class PackB {
public:
    PackB(Context& ctx, const GemmParams& p);
    cl_event enqueue(Context& ctx, cl_mem x, std::size_t x_off, int K, int N, cl_mem bp, std::size_t bp_off, Act act,
                     bool want_event = false);

private:
    GemmParams p_;
    Kernel kernel_;
};

class Gemm {
public:
    // Builds gemm_packed (p.kwg == 0) or gemm_local (p.kwg > 0). Throws InputError when a gemm_local set does not
    // fit the device (local memory, work-group size): the self-check reports that as the variant's reason.
    Gemm(Context& ctx, const GemmParams& p);
    const GemmParams& params() const { return p_; }
    // C[m][n] (at c_off, row stride ldc) = act(scale[m] * (A B)[m][n] + shift[m]).
    cl_event enqueue(Context& ctx, int M, int N, int K, cl_mem ap, cl_mem bp, std::size_t b_off, cl_mem c, std::size_t c_off, int ldc,
                     cl_mem scale, cl_mem shift, Act act, bool want_event = false);

private:
    GemmParams p_;
    Kernel kernel_;
};

}  // namespace ngi::detail
