#include "ops/gemm.hpp"

#include <cstdio>

#include "ngi/error.hpp"

namespace ngi::detail {

std::string GemmParams::defines() const {
    std::string d = "-DMR=" + std::to_string(mr) + " -DVW=" + std::to_string(vw) + " -DNV=" + std::to_string(nv) +
                    " -DKU=" + std::to_string(ku) + " -DUNROLL=" + std::to_string(unroll);
    // gemm_local: the work-group shape sizes its local arrays (reqd_work_group_size). gemm_packed's defines stay
    // as they were, so its cached programs and self-check verdicts stay valid.
    if (kwg > 0)
        d += " -DKWG=" + std::to_string(kwg) + " -DL0=" + std::to_string(local0) + " -DL1=" + std::to_string(local1);
    return d;
}

std::string GemmParams::to_string() const {
    std::string s = std::to_string(mr) + "," + std::to_string(vw) + "," + std::to_string(nv) + "," +
                    std::to_string(ku) + "," + std::to_string(local0) + "," + std::to_string(local1) + "," +
                    std::to_string(unroll);
    if (kwg > 0) {  // gemm_packed's sets print as before the knob existed
        s += ',';     // (not s += "," + ...: GCC 12 warns -Wrestrict on it, PR105329)
        s += std::to_string(kwg);
    }
    return s;
}

bool operator==(const GemmParams& a, const GemmParams& b) { return a.to_string() == b.to_string(); }

GemmParams parse_gemm_params(const std::string& s) {
    GemmParams p;
    char tail = 0;
    const int n = std::sscanf(s.c_str(), "%d,%d,%d,%d,%d,%d,%d,%d%c", &p.mr, &p.vw, &p.nv, &p.ku, &p.local0,
                              &p.local1, &p.unroll, &p.kwg, &tail);
    if ((n < 6 || n > 8) || p.mr < 1 || p.mr > 16 ||
        !(p.vw == 1 || p.vw == 2 || p.vw == 4 || p.vw == 8 || p.vw == 16) || p.nv < 1 || p.nv > 8 || p.ku < 1 ||
        p.ku > 16 || p.local0 < 1 || p.local1 < 1 || p.local0 > 1024 || p.local1 > 1024 ||
        !(p.unroll == 0 || p.unroll == 1) || p.kwg < 0 || p.kwg > 1024)
        throw InputError("GEMM parameters '" + s + "': expected MR,VW,NV,KU,L0,L1[,UNROLL[,KWG]] with MR 1..16, VW "
                         "in {1,2,4,8,16}, NV 1..8, KU 1..16, L0,L1 1..1024, UNROLL 0 or 1, KWG 0..1024");
    if (n == 6) p.unroll = 1;
    if (n < 8) p.kwg = 0;
    if (p.kwg % p.ku != 0)  // a chunk holds whole unroll steps
        throw InputError("GEMM parameters '" + s + "': KWG " + std::to_string(p.kwg) + " is not a multiple of KU " +
                         std::to_string(p.ku));
    if (p.kwg > 0 && std::size_t(p.local0) * std::size_t(p.local1) > 1024)
        throw InputError("GEMM parameters '" + s + "': the local-memory kernel (KWG > 0) runs work-groups of exactly "
                         "L0 x L1 = " + std::to_string(p.local0 * p.local1) + " work-items; at most 1024");
    return p;
}

std::vector<float> pack_a(const float* a, int M, int K, int ld, const GemmParams& p) {
    const int panels = (M + p.mr - 1) / p.mr;
    const int kp = padded_k(K, p);
    std::vector<float> out(std::size_t(panels) * kp * p.mr, 0.0f);
    for (int m = 0; m < M; ++m)
        for (int k = 0; k < K; ++k)
            out[(std::size_t(m / p.mr) * kp + k) * p.mr + m % p.mr] = a[std::size_t(m) * ld + k];
    return out;
}

std::vector<float> pack_b(const float* b, int K, int N, int ld, const GemmParams& p) {
    const int nr = p.nr(), kp = padded_k(K, p);
    std::vector<float> out(packed_b_floats(K, N, p), 0.0f);
    for (int k = 0; k < K; ++k)
        for (int n = 0; n < N; ++n) out[(std::size_t(n / nr) * kp + k) * nr + n % nr] = b[std::size_t(k) * ld + n];
    return out;
}

namespace {

// A gemm_local knob set must fit the device before it is built: its local arrays are sized at compile time, and
// its work-group shape is part of the algorithm, so Context::launch runs it as it is.
const GemmParams& fits_device(const Context& ctx, const GemmParams& p) {
    if (p.kwg == 0) return p;
    const DeviceInfo& info = ctx.info();
    if (p.local_mem_bytes() > info.local_mem_bytes)
        throw InputError("GEMM parameters " + p.to_string() + ": the local-memory kernel needs (L0 " +
                         std::to_string(p.local0) + " x MR " + std::to_string(p.mr) + " + L1 " +
                         std::to_string(p.local1) + " x NR " + std::to_string(p.nr()) + ") x KWG " +
                         std::to_string(p.kwg) + " x 4 = " + std::to_string(p.local_mem_bytes()) +
                         " bytes of local memory; " + info.name + " has " + std::to_string(info.local_mem_bytes) +
                         " (CL_DEVICE_LOCAL_MEM_SIZE)");
    const std::size_t items = std::size_t(p.local0) * std::size_t(p.local1);
    if (items > info.max_work_group_size)
        throw InputError("GEMM parameters " + p.to_string() + ": the local-memory kernel runs work-groups of exactly "
                         "L0 x L1 = " + std::to_string(items) + " work-items; " + info.name + " allows " +
                         std::to_string(info.max_work_group_size) + " (CL_DEVICE_MAX_WORK_GROUP_SIZE)");
    return p;
}

}  // namespace

// gemm_packed (KWG 0): the work-group shape L0 x L1 is a performance knob only (no local memory, no barriers):
// where the compiled kernel allows fewer work-items (CL_KERNEL_WORK_GROUP_SIZE; rusticl reports 32),
// Context::launch halves it. gemm_local (KWG > 0) is compiled with reqd_work_group_size(L0, L1, 1), which makes
// it a fixed-shape kernel (Kernel::fixed_local): launched at exactly L0 x L1, never halved.
Gemm::Gemm(Context& ctx, const GemmParams& p)
    : p_(fits_device(ctx, p)), kernel_(ctx.kernel("gemm", p.kwg > 0 ? "gemm_local" : "gemm_packed", gemm_kernel_defines(p))) {}

PackB::PackB(Context& ctx, const GemmParams& p)
    : p_(p), kernel_(ctx.kernel("im2col", "pack_panels", im2col_defines(p.nr()))) {}

cl_event PackB::enqueue(Context& ctx, cl_mem x, std::size_t x_off, int K, int N, cl_mem bp, std::size_t bp_off,
                        Act act, bool want_event) {
    static const std::size_t local[2] = {16, 1};  // fixed: PoCL compiles one work-group function per local size
    kernel_.args(x, int(x_off), K, N, padded_k(K, p_), bp, int(bp_off), int(act.kind), act.alpha);
    const std::size_t global[2] = {std::size_t(padded_k(K, p_)), std::size_t((N + p_.nr() - 1) / p_.nr())};
    return ctx.launch(kernel_, 2, global, local, want_event);
}

cl_event Gemm::enqueue(Context& ctx, int M, int N, int K, cl_mem ap, cl_mem bp, std::size_t b_off, cl_mem c, std::size_t c_off, int ldc,
                       cl_mem scale, cl_mem shift, Act act, bool want_event) {
    kernel_.args(M, N, padded_k(K, p_), ap, bp, int(b_off), c, int(c_off), ldc, scale, shift, int(act.kind), act.alpha);
    const std::size_t global[2] = {std::size_t((M + p_.mr - 1) / p_.mr), std::size_t((N + p_.nr() - 1) / p_.nr())};
    const std::size_t local[2] = {std::size_t(p_.local0), std::size_t(p_.local1)};
    return ctx.launch(kernel_, 2, global, local, want_event);
}

}  // namespace ngi::detail
