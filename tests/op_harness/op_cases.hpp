// The op harness's table (in the spirit of ggml's test-backend-ops): one row per case of every public entry point of
// host/src/ops/, each declaring its shapes, its tolerance as a normalized error, and FLOPs and bytes for the perf
// mode. Every buffer the op touches is guarded (op_harness/guarded_buffer.hpp). The correctness run
// (tests/test_op_harness.cpp) and the benchmark (perf/op_bench.cpp) use the same rows, at Size::Test and
// Size::Perf. A new op gets its rows here (docs/ARCHITECTURE.md, "Where a change goes").
#pragma once
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "op_harness/guarded_buffer.hpp"
#include "ops/gemm.hpp"
#include "runtime/context.hpp"

namespace ngi::harness {

// Test: odd, non-tile-multiple shapes small enough for a double reference (or tiny, for oclgrind); Perf: shapes of
// the models' real layers and frames, for timing only (no reference is computed).
enum class Size { Test, Perf };

// The normalized error of a case: max_i |got_i - want_i| / max(max_i |want_i|, 1e-30), over the elements not
// skipped; infinite when got has a NaN or Inf where want is finite. The max norm rather than ggml's NMSE (a sum of
// squares over the whole output): an out-of-bounds or indexing bug damages a few elements, which a mean over
// 10^5 elements would dilute below any useful tolerance, while one wrong element sets the max. Dividing by the
// output's largest magnitude makes it unit-free, so one tolerance holds across input scales; fp32 rounding then
// shows up as a few ulp of the largest output (~1e-7), accumulation over K as ~sqrt(K) ulp. It is tests/compare.hpp's
// scaled kind: run_case compares with Tol::scaled(tolerance), and the error is that comparison's max_abs / scale.

// What the case compares after one run: the op's output and its reference, element for element; elements the
// reference marks as ambiguous (e.g. JBU's fallback decisions within 1% of the threshold) in `skip`; anything that
// must hold exactly (counts an op returns) as a non-empty `mismatch`.
struct Comparison {
    std::vector<float> got;
    std::vector<double> want;
    std::vector<char> skip;
    std::string mismatch;
};

// One case set up on a device: its guarded buffers, the op, and how to check it.
struct Prepared {
    std::string shape;               // "M37 N67 K45", for reports
    double flops = 0, bytes = 0;     // per run: arithmetic and the bytes the op must move at least (inputs + outputs)
    std::vector<std::shared_ptr<GuardedBuffer>> buffers;
    std::function<void(detail::Context&)> run;             // enqueues the op only (perf repeats it)
    std::function<Comparison(detail::Context&)> compare;   // after one run: output vs reference
};

struct OpCase {
    std::string op;    // the entry point: "Gemm::enqueue", "Elementwise::sanitize", ...
    std::string name;  // the case within the op
    bool tiny = false; // small enough for oclgrind ([op_harness][oclgrind])
    double tolerance = 0;  // on normalized_error
    std::function<Prepared(detail::Context&, Size, std::mt19937&)> prepare;
    std::string id() const { return op + " / " + name; }
};

// Every case. Built once; the GEMM knob sets come from gemm_variants(), gemm_extreme_variants() and
// gemm_local_variants().
const std::vector<OpCase>& op_cases();

// The RNG a case's prepare gets (run_case, perf/op_bench): seeded from the case's id (FNV-1a), so every run and
// device sees the same data and the same randomly drawn shapes, independent of the table's order.
std::mt19937 case_rng(const OpCase& c);

// The GEMM knob sets the table picks for a GPU and for a CPU, each with its fallback chain, without duplicates: the
// same sets as test::gpu_and_cpu_gemm_variants() (tests/test_support.hpp, which the harness cannot include: it
// pulls in Catch2, and perf/op_bench links the harness without it); test_op_harness.cpp checks they agree.
std::vector<detail::GemmParams> gemm_variants();

// Knob sets beyond the tuning table that the GEMM rows run too (tests/test_gemm.cpp also runs them at the generators'
// layer shapes): small micro-kernels with one knob at its extreme (MR 16, NV 8, KU 16, VW 16, work-groups 4 wide, the
// loop form); and gemm_local's (KWG > 0): square, tall and wide work-groups, VW 2..8, NV 1..2, KU 2, a KWG that is
// not a power of two, MR 3, both UNROLL forms.
std::vector<detail::GemmParams> gemm_extreme_variants();
std::vector<detail::GemmParams> gemm_local_variants();

// Whether a convolution asked for the implicit path (ConvPath::implicit) takes it at the small shapes of the tests:
// an exact geometry (the stride divides the kernel; transposed: also K - 2P = S on both axes), an input activation
// conv_pad applies (none, ReLU, LeakyReLU) and a gemm_packed knob set (KWG 0). Otherwise it keeps im2col / col2im.
bool conv_takes_implicit(int kh, int kw, int stride, int pad, int in_act, bool transposed,
                         const detail::GemmParams& gp);

struct Outcome {
    std::string shape;
    double error = 0;     // the normalized error
    std::string worst;    // the comparison's report: the worst element, both values, the bound (tests/compare.hpp)
    std::string failure;  // a damaged guard, a written input or an exact mismatch; empty when none
    bool passed(double tolerance) const { return failure.empty() && error <= tolerance; }
};

// Prepares the case (RNG seeded from its id, so every run sees the same data), runs it once, waits, checks every
// buffer's guards and compares with the reference.
Outcome run_case(detail::Context& ctx, const OpCase& c, Size size = Size::Test);

}  // namespace ngi::harness
