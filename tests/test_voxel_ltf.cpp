// Seed 004's light-transition function (ops/voxel_ltf.*) against the double-precision reference
// (tests/reference_voxel.hpp): both variants, with and without a visibility mask, odd voxel counts, any split of
// the senders over launches, energy bounds, a closed-form pair, extreme values and bad input.
// The op harness's rows (tests/op_harness/op_cases.cpp) are the op's oracle at odd shapes, every buffer guarded;
// each case here says on its first line why it is outside the harness. Comparisons: tests/compare.hpp.
#include <chrono>
#include <ctime>
#include <cstdint>
#include <cstdio>

#include "ops/voxel_ltf.hpp"
#include "reference_voxel.hpp"
#include "test_support.hpp"

using namespace ngi;
using namespace ngi::detail;

namespace {

// A random voxel set: integer block centres (+0.5) in a cube of side `extent` (a voxel scene's geometry; repeated
// blocks allowed), axis or random unit normals, random exposed faces, albedo in [0, 1], direct in [0, 2].
test::LtfScene random_scene(int V, std::mt19937& rng, int extent = 12) {
    test::LtfScene s;
    s.voxels = V;
    s.position.resize(std::size_t(4) * V);
    s.normal.resize(s.position.size());
    s.albedo.resize(s.position.size());
    s.direct.resize(s.position.size());
    s.exposed.resize(V);
    std::uniform_int_distribution<int> cell(0, extent - 1), face(0, 5);
    std::uniform_real_distribution<float> u01(0.0f, 1.0f);
    std::normal_distribution<float> g(0.0f, 1.0f);
    for (int i = 0; i < V; ++i) {
        float* p = &s.position[std::size_t(4) * i];
        float* n = &s.normal[std::size_t(4) * i];
        for (int c = 0; c < 3; ++c) p[c] = float(cell(rng)) + 0.5f;
        if (i % 3 == 0) {  // a smooth normal
            float len = 0;
            for (int c = 0; c < 3; ++c) { n[c] = g(rng); len += n[c] * n[c]; }
            len = std::sqrt(len);
            for (int c = 0; c < 3; ++c) n[c] /= len;
        } else {  // a face normal
            const int f = face(rng);
            n[f >> 1] = (f & 1) ? -1.0f : 1.0f;
        }
        s.exposed[i] = 1u + std::uint32_t(rng() % 63);
        for (int c = 0; c < 3; ++c) {
            s.albedo[std::size_t(4) * i + c] = u01(rng);
            s.direct[std::size_t(4) * i + c] = 2.0f * u01(rng);
        }
    }
    return s;
}

std::vector<std::uint32_t> random_mask(int V, std::mt19937& rng) {
    const int words = (V + 31) / 32;
    std::vector<std::uint32_t> m(std::size_t(V) * words);
    // About a quarter of the pairs visible, more in every third word: sparse and dense rows of the mask.
    for (auto& w : m) w = std::uint32_t(rng()) & std::uint32_t(rng());
    for (std::size_t k = 0; k < m.size(); k += 3) m[k] |= std::uint32_t(rng());
    return m;
}

template <class T>
Buffer upload_raw(const std::vector<T>& v) {
    Buffer b = test::ctx().alloc(std::max<std::size_t>(1, v.size()) * sizeof(T), "test input");
    if (!v.empty()) test::ctx().write(b, 0, v.size() * sizeof(T), v.data(), "test input");
    return b;
}

// The scene on the device, as the op takes it.
struct DeviceScene {
    Buffer position, normal, albedo, direct, exposed;
    LtfInputs inputs;
    explicit DeviceScene(const test::LtfScene& s)
        : position(upload_raw(s.position)), normal(upload_raw(s.normal)), albedo(upload_raw(s.albedo)),
          direct(upload_raw(s.direct)), exposed(upload_raw(s.exposed)) {
        inputs.voxels = s.voxels;
        inputs.position = position.get();
        inputs.normal = normal.get();
        inputs.albedo = albedo.get();
        inputs.direct = direct.get();
        inputs.exposed = exposed.get();
    }
};

std::vector<float> run_ltf(VoxelLtf& op, const DeviceScene& ds, int bounces, LtfVariant variant, const Buffer* mask,
                           std::vector<double>* energy = nullptr) {
    auto& ctx = test::ctx();
    Buffer out = ctx.alloc(std::size_t(4) * ds.inputs.voxels * sizeof(float), "test out");
    op.run(ctx, ds.inputs, bounces, variant, mask ? mask->get() : nullptr, out.get(), energy);
    return test::download(out, std::size_t(4) * ds.inputs.voxels);
}

// The LTF's sums over V senders per bounce: 2e-5 of each value, or 1e-6 of the largest (values near zero).
const test::Tol kLtf = test::Tol::relative(2e-5, "float sums over V senders, bounce after bounce").or_scaled(1e-6);
// A two-voxel exchange: a few roundings per bounce.
const test::Tol kClosedForm = test::Tol::relative(1e-6, "two voxels, a few roundings per bounce");

const char* name_of(LtfVariant v) { return v == LtfVariant::Physical ? "physical" : "as written"; }
const char* shape_name(LtfKernelShape s) {
    return s == LtfKernelShape::Plain ? "plain" : s == LtfKernelShape::Tiled ? "tiled" : "vector";
}

}  // namespace

// Outside the harness: the energy diagnostic, bounces 0 and 3, V 1 to 513 (the rows: V 97, 2 bounces).
TEST_CASE("voxel LTF: both variants, every kernel shape = the double reference (odd V, bounces 0/1/3, mask)", "[ltf]") {
    std::mt19937 rng(4001);
    auto& ctx = test::ctx();
    VoxelLtf plain(ctx, LtfKernelShape::Plain), tiled(ctx, LtfKernelShape::Tiled), vector(ctx, LtfKernelShape::Vector);
    for (int V : {1, 2, 31, 33, 64, 257, 513}) {
        const test::LtfScene s = random_scene(V, rng, V < 40 ? 4 : 12);
        const DeviceScene ds(s);
        const std::vector<std::uint32_t> mask = random_mask(V, rng);
        const Buffer mask_buffer = upload_raw(mask);
        for (LtfVariant variant : {LtfVariant::Physical, LtfVariant::AsWritten})
            for (int use_mask = 0; use_mask < (variant == LtfVariant::Physical ? 2 : 1); ++use_mask)
                for (int bounces : {0, 1, 3}) {
                    std::vector<double> want_energy;
                    const std::vector<double> want = test::ltf_reference(s, bounces, variant == LtfVariant::Physical,
                                                                         use_mask ? &mask : nullptr, &want_energy);
                    for (VoxelLtf* op : {&plain, &tiled, &vector}) {
                        CAPTURE(V, name_of(variant), use_mask, bounces, int(op->shape()));
                        std::vector<double> energy;
                        const std::vector<float> got =
                            run_ltf(*op, ds, bounces, variant, use_mask ? &mask_buffer : nullptr, &energy);
                        test::require_close(got, want, kLtf);
                        REQUIRE(energy.size() == want_energy.size());
                        test::require_close(energy, want_energy, kLtf.of(std::abs(want_energy[0])));
                    }
                }
    }
}

// Outside the harness: bit-exactness across splits of the senders (a knob).
TEST_CASE("voxel LTF: any split of the senders over launches gives bit-identical results", "[ltf]") {
    std::mt19937 rng(4002);
    auto& ctx = test::ctx();
    const int V = 301;
    const test::LtfScene s = random_scene(V, rng);
    const DeviceScene ds(s);
    const Buffer mask = upload_raw(random_mask(V, rng));
    for (LtfKernelShape shape : {LtfKernelShape::Plain, LtfKernelShape::Tiled, LtfKernelShape::Vector}) {
        VoxelLtf op(ctx, shape);
        for (LtfVariant variant : {LtfVariant::Physical, LtfVariant::AsWritten}) {
            const Buffer* m = variant == LtfVariant::Physical ? &mask : nullptr;
            op.set_max_senders_per_launch(0);
            const std::vector<float> whole = run_ltf(op, ds, 2, variant, m);
            // Without the energy diagnostic a run stays on the device: no host transfer.
            Buffer out = ctx.alloc(std::size_t(4) * V * sizeof(float), "test out");
            const HostTransfers t0 = ctx.transfers();
            op.run(ctx, ds.inputs, 2, variant, m ? m->get() : nullptr, out.get());
            const HostTransfers t1 = ctx.transfers();
            REQUIRE(t1.uploads == t0.uploads);
            REQUIRE(t1.downloads == t0.downloads);
            for (int cap : {1, 37, 64, 300}) {
                CAPTURE(int(shape), name_of(variant), cap);
                op.set_max_senders_per_launch(cap);
                const std::vector<float> split = run_ltf(op, ds, 2, variant, m);
                test::require_close(split, whole, test::Tol::bits());
            }
        }
    }
}

// Outside the harness: a property (the energy never grows) over 8 bounces.
TEST_CASE("voxel LTF as written: the energy of E^t never grows when every albedo <= 1", "[ltf]") {
    std::mt19937 rng(4003);
    auto& ctx = test::ctx();
    VoxelLtf op(ctx);
    const int bounces = 8;
    for (int V : {2, 3, 40, 301}) {
        for (int white = 0; white < 2; ++white) {
            // Dense clusters are the worst case of the unnormalized formula (many close senders).
            test::LtfScene s = random_scene(V, rng, V < 40 ? 2 : 5);
            if (white)
                for (int i = 0; i < V; ++i)
                    for (int c = 0; c < 3; ++c) s.albedo[std::size_t(4) * i + c] = 1.0f;
            const DeviceScene ds(s);
            std::vector<double> energy;
            const std::vector<float> out = run_ltf(op, ds, bounces, LtfVariant::AsWritten, nullptr, &energy);
            CAPTURE(V, white);
            REQUIRE(energy.size() == std::size_t(bounces + 1));
            for (int k = 0; k < bounces; ++k) {
                CAPTURE(k);
                REQUIRE(energy[k + 1] <= energy[k] * (1 + 1e-5) + 1e-30);
            }
            // The output is E^0 + ... + E^t: its luminance sums to the sum of the energies, at most (t + 1) E^0.
            double total = 0, sum = 0;
            for (int i = 0; i < V; ++i) {
                const double c[3] = {out[std::size_t(4) * i], out[std::size_t(4) * i + 1], out[std::size_t(4) * i + 2]};
                total += test::ref_luminance(c);
            }
            for (double e : energy) sum += e;
            test::require_value(total, sum, test::Tol::relative(1e-5, "float luminances of V voxels summed in double"));
            REQUIRE(total <= (bounces + 1) * energy[0] * (1 + 1e-5));
        }
    }
}

// Outside the harness: an external oracle (the closed form).
TEST_CASE("voxel LTF physical: two facing voxels exchange light with the closed-form G = 1 / (pi r^2)", "[ltf]") {
    auto& ctx = test::ctx();
    VoxelLtf op(ctx);
    const float d0[3] = {2.0f, 1.0f, 0.5f}, d1[3] = {0.25f, 3.0f, 1.0f};
    const float rho0[3] = {0.8f, 0.5f, 0.2f}, rho1[3] = {0.3f, 0.9f, 0.6f};
    // D = 0.3 m is below r_min: the clamp (r_min = 0.5 m) must take over.
    for (double D : {7.0, 20.0, 0.3}) {
        for (int facing = 0; facing < 2; ++facing) {
            test::LtfScene s;
            s.voxels = 2;
            s.position = {0.5f, 2.5f, 1.5f, 0.0f, float(0.5 + D), 2.5f, 1.5f, 0.0f};
            // Voxel 0 looks along +x with its +x face exposed; voxel 1 looks back along -x with its -x face exposed
            // (or, not facing, voxel 0 looks away with its -x face).
            s.normal = {facing ? 1.0f : -1.0f, 0, 0, 0, -1.0f, 0, 0, 0};
            s.exposed = {facing ? 1u : 2u, 2u};
            s.albedo = {rho0[0], rho0[1], rho0[2], 0, rho1[0], rho1[1], rho1[2], 0};
            s.direct = {d0[0], d0[1], d0[2], 0, d1[0], d1[1], d1[2], 0};
            const DeviceScene ds(s);
            const double g = facing ? 1.0 / (M_PI * std::max(D * D, 0.25)) : 0.0;
            for (int bounces : {1, 2, 5}) {
                // L^{t+1}_0 = d0 + g rho1 L^t_1, L^{t+1}_1 = d1 + g rho0 L^t_0, from L^0 = d.
                double L0[3], L1[3];
                for (int c = 0; c < 3; ++c) { L0[c] = d0[c]; L1[c] = d1[c]; }
                for (int b = 0; b < bounces; ++b)
                    for (int c = 0; c < 3; ++c) {
                        const double n0 = d0[c] + g * rho1[c] * L1[c], n1 = d1[c] + g * rho0[c] * L0[c];
                        L0[c] = n0;
                        L1[c] = n1;
                    }
                const std::vector<float> got = run_ltf(op, ds, bounces, LtfVariant::Physical, nullptr);
                CAPTURE(D, facing, bounces);
                test::require_close(std::span<const float>(got).first(3), L0, kClosedForm);
                test::require_close(std::span<const float>(got).subspan(4, 3), L1, kClosedForm);
                if (bounces == 1 && facing)  // the first bounce spelled out: d_0 + rho_1 d_1 / (pi r^2)
                    test::require_value(got[0], d0[0] + rho1[0] * d1[0] / (M_PI * std::max(D * D, 0.25)), kClosedForm);
            }
        }
    }
}

// Outside the harness: extremes (d = 1e6, rho = 0, coincident voxels).
TEST_CASE("voxel LTF: extreme values (d = 1e6, rho = 0, coincident voxels) stay finite and exact", "[ltf]") {
    std::mt19937 rng(4005);
    auto& ctx = test::ctx();
    VoxelLtf op(ctx);
    const int V = 97;
    test::LtfScene s = random_scene(V, rng, 3);
    for (int i = 0; i < V; i += 5)
        for (int c = 0; c < 3; ++c) s.direct[std::size_t(4) * i + c] = 1.0e6f;
    for (int i = 1; i < V; i += 7)
        for (int c = 0; c < 3; ++c) s.albedo[std::size_t(4) * i + c] = 0.0f;
    for (int i = 0; i < 10; ++i)  // ten voxels at one point: r = 0 between them
        for (int c = 0; c < 3; ++c) s.position[std::size_t(4) * i + c] = 1.5f;
    const DeviceScene ds(s);
    for (LtfVariant variant : {LtfVariant::Physical, LtfVariant::AsWritten}) {
        const std::vector<double> want = test::ltf_reference(s, 3, variant == LtfVariant::Physical, nullptr);
        const std::vector<float> got = run_ltf(op, ds, 3, variant, nullptr);
        CAPTURE(name_of(variant));
        test::require_close(got, want, kLtf);  // a NaN or Inf in got fails it
    }
    // Every albedo 0: no light is reflected, both variants return d exactly.
    for (std::size_t k = 0; k < s.albedo.size(); ++k) s.albedo[k] = 0.0f;
    const DeviceScene black(s);
    for (LtfVariant variant : {LtfVariant::Physical, LtfVariant::AsWritten}) {
        const std::vector<float> got = run_ltf(op, black, 3, variant, nullptr);
        CAPTURE(name_of(variant));
        test::require_close(got, s.direct, test::Tol::bits());
    }
}

// Outside the harness: refusals.
TEST_CASE("voxel LTF: bad input is an InputError naming it", "[ltf]") {
    std::mt19937 rng(4006);
    auto& ctx = test::ctx();
    VoxelLtf op(ctx);
    const test::LtfScene s = random_scene(9, rng);
    const DeviceScene ds(s);
    Buffer out = ctx.alloc(9 * 4 * sizeof(float), "test out");
    Buffer small = ctx.alloc(8 * 4 * sizeof(float), "test small"), word = ctx.alloc(4, "test word");
    const Buffer mask = upload_raw(random_mask(9, rng));
    auto fails = [&](LtfInputs in, int bounces, LtfVariant v, cl_mem vis, cl_mem o, const std::string& what) {
        CAPTURE(what);
        try {
            op.run(ctx, in, bounces, v, vis, o);
            FAIL("no InputError");
        } catch (const InputError& e) {
            CHECK_THAT(e.what(), Catch::Contains(what));
        }
    };
    LtfInputs in = ds.inputs;
    fails(in, -1, LtfVariant::Physical, nullptr, out.get(), "bounces");
    fails(in, kLtfMaxBounces + 1, LtfVariant::Physical, nullptr, out.get(), "bounces");
    fails(in, 1, LtfVariant::AsWritten, mask.get(), out.get(), "visibility mask");
    fails(in, 1, LtfVariant::Physical, word.get(), out.get(), "visibility");  // 9 rows of 1 word needed
    fails(in, 1, LtfVariant::Physical, nullptr, small.get(), "output");
    fails(in, 1, LtfVariant::Physical, nullptr, ds.direct.get(), "output buffer is also an input");
    in.voxels = 0;
    fails(in, 1, LtfVariant::Physical, nullptr, out.get(), "0 voxels");
    in.voxels = kLtfMaxVoxels + 1;
    fails(in, 1, LtfVariant::Physical, nullptr, out.get(), "voxels");
    in = ds.inputs;
    in.albedo = small.get();
    fails(in, 1, LtfVariant::Physical, nullptr, out.get(), "albedo");
    in = ds.inputs;
    in.exposed = nullptr;
    fails(in, 1, LtfVariant::Physical, nullptr, out.get(), "exposed");
}

// Outside the harness: the energy diagnostic and the plain kernel under oclgrind.
TEST_CASE("voxel LTF at a small shape (oclgrind: bounds, races, uninitialized reads)", "[oclgrind][ltf]") {
    std::mt19937 rng(4007);
    auto& ctx = test::ctx();
    const int V = 5;
    const test::LtfScene s = random_scene(V, rng, 3);
    const DeviceScene ds(s);
    const std::vector<std::uint32_t> mask = random_mask(V, rng);
    const Buffer mask_buffer = upload_raw(mask);
    for (LtfKernelShape shape : {LtfKernelShape::Plain, LtfKernelShape::Tiled, LtfKernelShape::Vector}) {
        VoxelLtf op(ctx, shape);
        op.set_max_senders_per_launch(3);  // two launches per bounce: the running sum
        for (LtfVariant variant : {LtfVariant::Physical, LtfVariant::AsWritten}) {
            const bool physical = variant == LtfVariant::Physical;
            std::vector<double> energy, want_energy;
            const std::vector<double> want = test::ltf_reference(s, 2, physical, physical ? &mask : nullptr, &want_energy);
            const std::vector<float> got = run_ltf(op, ds, 2, variant, physical ? &mask_buffer : nullptr, &energy);
            CAPTURE(int(shape), name_of(variant));
            test::require_close(got, want, kLtf);
            test::require_close(energy, want_energy, test::Tol::relative(1e-5, "the energy of a 5-voxel scene"));
        }
    }
}

// Timing (not part of the suite): ms per bounce at V = 10,000 random voxels for both variants and shapes, and on a
// driver with a loop limit, a run beyond it (V = 70,000 senders split over launches) checked on sampled receivers.
// Outside the harness: timing (not run by the suite).
TEST_CASE("voxel LTF timing: ms per bounce at V = 10,000", "[.][ltf-perf]") {
    std::mt19937 rng(4008);
    auto& ctx = test::ctx();
    const int V = 10000;
    const test::LtfScene s = random_scene(V, rng, 40);
    const DeviceScene ds(s);
    const Buffer mask = upload_raw(random_mask(V, rng));
    Buffer out = ctx.alloc(std::size_t(4) * V * sizeof(float), "test out");
    for (LtfKernelShape shape : {LtfKernelShape::Plain, LtfKernelShape::Tiled, LtfKernelShape::Vector}) {
        VoxelLtf op(ctx, shape);
        for (LtfVariant variant : {LtfVariant::Physical, LtfVariant::AsWritten})
            for (int use_mask = 0; use_mask < (variant == LtfVariant::Physical ? 2 : 1); ++use_mask) {
                cl_mem m = use_mask ? mask.get() : nullptr;
                op.run(ctx, ds.inputs, 1, variant, m, out.get());  // warm up: build, allocate
                ctx.finish();
                // The best of three runs of 1 and of 3 bounces (the machine may be shared); the difference over 2
                // is the bounce alone, without the per-run setup (AsWritten's O(V^2) normalizer is setup). Also
                // the process CPU time (every driver thread), which other processes on the machine inflate less.
                double ms[2] = {1e30, 1e30}, cpu[2] = {1e30, 1e30};
                for (int rep = 0; rep < 3; ++rep)
                    for (int k = 0; k < 2; ++k) {
                        const auto t0 = std::chrono::steady_clock::now();
                        const std::clock_t c0 = std::clock();
                        op.run(ctx, ds.inputs, k == 0 ? 1 : 3, variant, m, out.get());
                        ctx.finish();
                        cpu[k] = std::min(cpu[k], 1e3 * double(std::clock() - c0) / CLOCKS_PER_SEC);
                        ms[k] = std::min(ms[k], std::chrono::duration<double, std::milli>(
                                                    std::chrono::steady_clock::now() - t0).count());
                    }
                std::printf("ltf-perf %s: %s %s%s: %.1f ms per bounce (%.1f ms CPU), %.1f ms for 1 bounce\n",
                            ctx.info().name.c_str(), shape_name(shape),
                            name_of(variant), use_mask ? " + mask" : "", (ms[1] - ms[0]) / 2, (cpu[1] - cpu[0]) / 2,
                            ms[0]);
            }
    }
    if (ctx.loop_limit() > 0) {
        const int W = 70000;  // beyond llvmpipe's 65,535 iterations: the senders must be split
        const test::LtfScene big = random_scene(W, rng, 60);
        const DeviceScene db(big);
        Buffer bo = ctx.alloc(std::size_t(4) * W * sizeof(float), "test out");
        VoxelLtf op(ctx);
        op.run(ctx, db.inputs, 1, LtfVariant::Physical, nullptr, bo.get());
        const std::vector<float> got = test::download(bo, std::size_t(4) * W);
        for (int i = 0; i < W; i += 6997) {
            double want[3] = {big.direct[std::size_t(4) * i], big.direct[std::size_t(4) * i + 1],
                              big.direct[std::size_t(4) * i + 2]};
            // Receiver i against every sender j, one two-voxel reference at a time (the reference's own pair factor).
            test::LtfScene pair;
            pair.voxels = 2;
            pair.position.resize(8);
            pair.normal.resize(8);
            pair.albedo.assign(8, 0.0f);
            pair.direct.assign(8, 0.0f);
            pair.exposed.resize(2);
            for (int j = 0; j < W; ++j) {
                if (j == i) continue;
                for (int c = 0; c < 4; ++c) {
                    pair.position[c] = big.position[std::size_t(4) * i + c];
                    pair.position[4 + c] = big.position[std::size_t(4) * j + c];
                    pair.normal[c] = big.normal[std::size_t(4) * i + c];
                    pair.albedo[4 + c] = big.albedo[std::size_t(4) * j + c];
                    pair.direct[4 + c] = big.direct[std::size_t(4) * j + c];
                }
                pair.exposed = {big.exposed[i], big.exposed[j]};
                const std::vector<double> one = test::ltf_reference(pair, 1, true, nullptr);
                for (int c = 0; c < 3; ++c) want[c] += one[c];  // receiver 0 of the pair: d = 0 there
            }
            CAPTURE(i);
            test::check_close(std::span<const float>(got).subspan(std::size_t(4) * i, 3), want,
                              test::Tol::relative(1e-4, "70,000 senders summed in float over launches"));
        }
    }
}
