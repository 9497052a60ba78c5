// The op harness (tests/op_harness/): every row of the table against its reference with its tolerance, every buffer
// guarded; one test case per op family, the tiny rows once more as the oclgrind subset; the table covers every
// entry point; and the guard check itself fails where it must. NGI_OP_HARNESS_REPORT=1 prints every case's
// normalized error (how docs/RELIABILITY.md's "Op harness" figures were measured).
#include <cstdio>
#include <cstdlib>
#include <set>

#include "op_harness/guarded_buffer.hpp"
#include "op_harness/op_cases.hpp"
#include "ops/elementwise.hpp"
#include "test_support.hpp"

using namespace ngi;
using namespace ngi::harness;

namespace {

bool starts_with_any(const std::string& op, std::initializer_list<const char*> prefixes) {
    for (const char* p : prefixes)
        if (op.rfind(p, 0) == 0) return true;
    return false;
}

// Runs the rows of the given ops (tiny rows only, or the others), each checked on its own.
void run_rows(std::initializer_list<const char*> ops, bool tiny) {
    const bool report = std::getenv("NGI_OP_HARNESS_REPORT") != nullptr;
    int ran = 0;
    for (const OpCase& c : op_cases()) {
        if (c.tiny != tiny || (ops.size() && !starts_with_any(c.op, ops))) continue;
        const Outcome o = run_case(test::ctx(), c, Size::Test);
        ++ran;
        if (report)
            std::printf("op_harness %-44s %-44s %-40s error %.3g tolerance %.3g\n", c.op.c_str(), c.name.c_str(),
                        o.shape.c_str(), o.error, c.tolerance);
        INFO(c.id() << " [" << o.shape << "]: normalized error " << o.error << ", tolerance " << c.tolerance
                    << (o.failure.empty() ? "" : "; " + o.failure) << "; " << o.worst);
        CHECK(o.failure.empty());
        CHECK(o.error <= c.tolerance);
    }
    REQUIRE(ran > 0);
}

}  // namespace

TEST_CASE("op harness: GEMM, PackB and Dense, every knob set", "[op_harness]") {
    run_rows({"Gemm::", "PackB::", "Dense::"}, false);
}

TEST_CASE("op harness: convolutions, both paths", "[op_harness]") {
    run_rows({"Conv2d::", "ConvTranspose2d::"}, false);
}

TEST_CASE("op harness: batch norm and elementwise ops", "[op_harness]") {
    run_rows({"BatchNormPerImage::", "Elementwise::"}, false);
}

TEST_CASE("op harness: MLPs and the frequency encoding", "[op_harness]") {
    run_rows({"FusedMlp::", "DenseMlp::", "FrequencyEncodePlanar::"}, false);
}

TEST_CASE("op harness: JBU, SH, set pooling, image gathering", "[op_harness]") {
    run_rows({"JointBilateralUpsample::", "ShEvaluate::", "SetPool::", "GatherImage::"}, false);
}

TEST_CASE("op harness: max pooling", "[op_harness]") {
    run_rows({"MaxPool2d::"}, false);
}

TEST_CASE("op harness: padding and bilinear resize", "[op_harness]") {
    run_rows({"Pad2d::", "ResizeBilinear::"}, false);
}

TEST_CASE("op harness: probe shading and the light-transition function", "[op_harness]") {
    run_rows({"ProbeShade::", "VoxelLtf::"}, false);
}

TEST_CASE("op harness: the tiny case of every op (the oclgrind subset)", "[op_harness][oclgrind]") {
    run_rows({}, true);
}

TEST_CASE("op harness: every op entry point has rows, a tiny one among them, and the GEMM sets are the tests'",
          "[op_harness]") {
    // Every public entry point of host/src/ops/ (a new op adds its name here and its rows to the table).
    const std::set<std::string> entry_points = {
        "Gemm::enqueue", "PackB::enqueue", "Dense::enqueue", "Conv2d::enqueue", "ConvTranspose2d::enqueue",
        "BatchNormPerImage::enqueue", "Elementwise::activate", "Elementwise::dropout",
        "Elementwise::sanitize + sanitized_count", "Elementwise::channel_affine", "Elementwise::add",
        "Elementwise::mul", "FusedMlp::enqueue", "DenseMlp::enqueue", "FrequencyEncodePlanar::enqueue",
        "JointBilateralUpsample::enqueue", "ShEvaluate::enqueue", "SetPool::pool", "SetPool::broadcast_concat",
        "SetPool::pool_planar", "GatherImage::enqueue", "ProbeShade::enqueue", "VoxelLtf::run",
        "MaxPool2d::enqueue", "Pad2d::enqueue", "ResizeBilinear::enqueue"};
    std::set<std::string> with_rows, with_tiny;
    for (const OpCase& c : op_cases()) {
        with_rows.insert(c.op);
        if (c.tiny) with_tiny.insert(c.op);
        CHECK(c.tolerance >= 0.0);
    }
    CHECK(with_rows == entry_points);
    CHECK(with_tiny == entry_points);
    CHECK(gemm_variants() == test::gpu_and_cpu_gemm_variants());
    // Every knob set has its row.
    for (const detail::GemmParams& p : gemm_variants()) {
        bool found = false;
        for (const OpCase& c : op_cases()) found |= c.op == "Gemm::enqueue" && c.name == "knobs " + p.to_string();
        CHECK(found);
    }
}

TEST_CASE("op harness: the guard check reports a damaged guard, a written input and an op's wrong offset",
          "[op_harness][oclgrind]") {
    auto& ctx = test::ctx();
    const std::vector<float> payload = {1.0f, 2.0f, 3.0f, 4.0f, 5.0f};
    const float one = 1.0f;
    SECTION("a word written just before the payload") {
        GuardedBuffer b(ctx, "x", Role::Output, payload.size(), nullptr);
        CHECK(b.check(ctx, "case").empty());
        detail::check(clEnqueueWriteBuffer(ctx.queue(), b.mem(), CL_TRUE, b.offset_bytes() - 4, 4, &one, 0, nullptr,
                                           nullptr),
                      "test", "clEnqueueWriteBuffer");
        CHECK_THAT(b.check(ctx, "case"), Catch::Contains("case: buffer 'x'") &&
                                             Catch::Contains("guard before the payload") &&
                                             Catch::Contains("first damaged word 0") && Catch::Contains("0x3f800000"));
    }
    SECTION("a word written three past the end") {
        GuardedBuffer b(ctx, "y", Role::Scratch, payload.size(), nullptr);
        detail::check(clEnqueueWriteBuffer(ctx.queue(), b.mem(), CL_TRUE, b.offset_bytes() + (payload.size() + 3) * 4,
                                           4, &one, 0, nullptr, nullptr),
                      "test", "clEnqueueWriteBuffer");
        CHECK_THAT(b.check(ctx, "case"),
                   Catch::Contains("guard after the payload") && Catch::Contains("first damaged word 3"));
    }
    SECTION("an input's payload changed") {
        GuardedBuffer b(ctx, "w", Role::Input, payload.size(), payload.data());
        CHECK(b.check(ctx, "case").empty());
        detail::check(clEnqueueWriteBuffer(ctx.queue(), b.mem(), CL_TRUE, b.offset_bytes() + 8, 4, &one, 0, nullptr,
                                           nullptr),
                      "test", "clEnqueueWriteBuffer");
        CHECK_THAT(b.check(ctx, "case"), Catch::Contains("an input the op wrote: payload word 2"));
        // The same write into an in-out buffer is the op's business.
        GuardedBuffer io(ctx, "io", Role::InOut, payload.size(), payload.data());
        detail::check(clEnqueueWriteBuffer(ctx.queue(), io.mem(), CL_TRUE, io.offset_bytes() + 8, 4, &one, 0, nullptr,
                                           nullptr),
                      "test", "clEnqueueWriteBuffer");
        CHECK(io.check(ctx, "case").empty());
    }
    SECTION("an op given an offset one element too far writes into the guard after") {
        detail::Elementwise ew(ctx);
        GuardedBuffer x(ctx, "x", Role::InOut, payload.size(), payload.data());
        GuardedBuffer y(ctx, "y", Role::Input, payload.size(), payload.data());
        const int n = int(payload.size());
        ew.add(ctx, detail::View{x.mem(), x.offset() + 1, {1, 1, n}}, detail::View{y.mem(), y.offset(), {1, 1, n}});
        ctx.finish();
        CHECK_THAT(x.check(ctx, "add, off by one"),
                   Catch::Contains("'x', guard after the payload, first damaged word 0"));
        CHECK(y.check(ctx, "add, off by one").empty());
    }
}
