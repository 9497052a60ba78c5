#include "ops/voxel_ltf.hpp"

#include "ops/buffer_checks.hpp"
#include "ops/luminance.hpp"
#include "runtime/kernel_defines.hpp"

#include <algorithm>
#include <string>
#include <utility>

namespace ngi::detail {

namespace {

constexpr int kLtfLocal = 64;  // the work-group size of every kernel of voxel_ltf.cl (LTF_LOCAL)
// What every voxel_ltf.cl kernel is built with (the gather adds its variant's options).
const std::string kLocalDefine =
    join_defines({define("LTF_LOCAL", kLtfLocal), define("LTF_R_MIN", kLtfRMin), luminance_defines()});
// Loop iterations a launch keeps in reserve below the driver's limit: the energy tree (log2 LTF_LOCAL) and
// whatever a compiler adds around the sender loop.
constexpr long kLoopSlack = 64;

void require_ltf_buffer(cl_mem m, std::size_t need, const std::string& name, int voxels) {
    detail::require_buffer(m, need, "voxel LTF", name, std::to_string(voxels) + " voxels");
}

std::size_t groups_of(int v) { return (std::size_t(v) + kLtfLocal - 1) / kLtfLocal; }

}  // namespace

VoxelLtf::VoxelLtf(Context& ctx, LtfKernelShape shape)
    : shape_(shape != LtfKernelShape::Auto ? shape
             : ctx.info().is_gpu           ? LtfKernelShape::Tiled
                                           : LtfKernelShape::Vector),
      pack_(ctx.kernel("voxel_ltf", "ltf_pack_geometry", kLocalDefine)),
      senders_(ctx.kernel("voxel_ltf", "ltf_senders", kLocalDefine)),
      accumulate_(ctx.kernel("voxel_ltf", "ltf_accumulate", kLocalDefine)),
      energy_(ctx.kernel("voxel_ltf", "ltf_energy", kLocalDefine)) {
    if (shape_ != LtfKernelShape::Plain && shape_ != LtfKernelShape::Tiled && shape_ != LtfKernelShape::Vector)
        throw InputError("voxel LTF: unknown kernel shape " + std::to_string(int(shape_)));
    // The normalizer sums over senders like the gather: the same receiver lanes.
    normalizer_ = ctx.kernel("voxel_ltf", "ltf_normalizer", kLocalDefine + " -DLTF_VEC=" + std::to_string(lanes()));
}

int VoxelLtf::lanes() const { return shape_ == LtfKernelShape::Vector ? kLtfVectorLanes : 1; }

Kernel& VoxelLtf::gather(Context& ctx, LtfVariant variant, bool vis) {
    const auto key = std::make_tuple(int(variant), int(vis));
    auto it = gathers_.find(key);
    if (it == gathers_.end()) {
        const std::string defines = kLocalDefine + " -DLTF_PHYSICAL=" + (variant == LtfVariant::Physical ? "1" : "0") +
                                    " -DLTF_VIS=" + (vis ? "1" : "0") +
                                    " -DLTF_TILED=" + (shape_ == LtfKernelShape::Tiled ? "1" : "0") +
                                    " -DLTF_VEC=" + std::to_string(lanes());
        it = gathers_.emplace(key, ctx.kernel("voxel_ltf", "ltf_gather", defines)).first;
    }
    return it->second;
}

int VoxelLtf::senders_per_launch(Context& ctx, bool tiled, int lanes, bool vis) const {
    long n = kLtfMaxVoxels;
    if (const long limit = ctx.loop_limit(); limit > 0) {
        // Loop iterations of one work-item for S senders (llvmpipe counts every loop of the kernel together):
        //   S sender iterations, plus
        //   tiled:         one tile iteration per LTF_LOCAL senders (at most S / LTF_LOCAL + 2)
        //   mask, untiled: per block of 32 senders one block iteration and `lanes` word loads (S / 32 + 2 blocks)
        //   2 lanes loops of `lanes` iterations (load and store of the receivers; within kLoopSlack)
        double per = 1.0, fixed = 0.0;
        if (tiled) { per += 1.0 / kLtfLocal; fixed += 2; }
        if (vis && !tiled) { per += (1.0 + lanes) / 32.0; fixed += 2.0 * (1 + lanes); }
        n = long((double(limit - kLoopSlack) - fixed) / per);
    }
    if (max_senders_ > 0) n = std::min<long>(n, max_senders_);
    return int(std::max<long>(n, 1));
}

void VoxelLtf::ensure_scratch(Context& ctx, int voxels) {
    if (voxels == scratch_voxels_) return;
    const std::size_t v4 = std::size_t(voxels) * 4 * sizeof(float);
    geometry_ = ctx.alloc(v4, "voxel LTF: sender geometry");
    mid_ = ctx.alloc(v4, "voxel LTF: sender exposed faces");
    half_ = ctx.alloc(v4, "voxel LTF: sender exposed faces");
    sender_ = ctx.alloc(v4, "voxel LTF: sender light");
    z_ = ctx.alloc(std::size_t(voxels) * sizeof(float), "voxel LTF: normalizers");
    ping_ = ctx.alloc(v4, "voxel LTF: iterate");
    pong_ = ctx.alloc(v4, "voxel LTF: iterate");
    scratch_voxels_ = voxels;
}

void VoxelLtf::run(Context& ctx, const LtfInputs& in, int bounces, LtfVariant variant, cl_mem visibility, cl_mem out,
                   std::vector<double>* energy) {
    const int V = in.voxels;
    if (V < 1 || V > kLtfMaxVoxels)
        throw InputError("voxel LTF: " + std::to_string(V) + " voxels (1 to " + std::to_string(kLtfMaxVoxels) +
                         " supported)");
    if (bounces < 0 || bounces > kLtfMaxBounces)
        throw InputError("voxel LTF: " + std::to_string(bounces) + " bounces (0 to " + std::to_string(kLtfMaxBounces) +
                         " supported)");
    if (variant != LtfVariant::Physical && variant != LtfVariant::AsWritten)
        throw InputError("voxel LTF: unknown variant " + std::to_string(int(variant)));
    if (visibility && variant == LtfVariant::AsWritten)
        throw InputError("voxel LTF: a visibility mask was given to the as-written variant, which has no shadow term "
                         "(seed 004 section 3.4)");
    const std::size_t v4 = std::size_t(V) * 4 * sizeof(float);
    require_ltf_buffer(in.position, v4, "position", V);
    require_ltf_buffer(in.normal, v4, "normal", V);
    require_ltf_buffer(in.albedo, v4, "albedo", V);
    require_ltf_buffer(in.direct, v4, "direct lighting", V);
    require_ltf_buffer(in.exposed, std::size_t(V) * sizeof(std::uint32_t), "exposed-faces", V);
    require_ltf_buffer(out, v4, "output", V);
    const int words = (V + 31) / 32;
    if (visibility) require_ltf_buffer(visibility, std::size_t(V) * words * sizeof(std::uint32_t), "visibility", V);
    for (cl_mem m : {in.position, in.normal, in.albedo, in.direct, in.exposed, visibility})
        if (m == out) throw InputError("voxel LTF: the output buffer is also an input");

    ensure_scratch(ctx, V);
    const std::size_t groups = groups_of(V);
    const std::size_t global = groups * kLtfLocal, local = kLtfLocal;
    const bool physical = variant == LtfVariant::Physical;
    if (energy) {
        const std::size_t need = std::size_t(bounces + 1) * groups * sizeof(float);
        if (partial_.bytes() < need) partial_ = ctx.alloc(need, "voxel LTF: energy partial sums");
    }
    auto measure = [&](cl_mem a, cl_mem b, int iterate) {
        if (!energy) return;
        energy_.args(a, b ? b : a, int(b != nullptr), V, partial_, int(std::size_t(iterate) * groups));
        ctx.launch(energy_, 1, &global, &local);
    };

    measure(in.direct, nullptr, 0);  // E^0 = L^0 = d (Physical: the increment from L^{-1} = 0)
    if (bounces == 0) {
        ctx.copy(in.direct, 0, out, 0, v4, "voxel LTF: d to the output");
    } else {
        pack_.args(in.position, in.exposed, V, geometry_, mid_, half_);
        ctx.launch(pack_, 1, &global, &local);
        const int chunk_plain = senders_per_launch(ctx, false, lanes(), false);
        // One work-item per lanes() receivers (normalizer and gather).
        const std::size_t lanes_global = groups_of((V + lanes() - 1) / lanes()) * kLtfLocal;
        if (!physical) {
            for (int k0 = 0; k0 < V; k0 += chunk_plain) {
                normalizer_.args(geometry_, V, k0, std::min(V, k0 + chunk_plain), int(k0 == 0), z_);
                ctx.launch(normalizer_, 1, &lanes_global, &local);
            }
            ctx.copy(in.direct, 0, out, 0, v4, "voxel LTF: E^0 to the running total");
        }
        Kernel& g = gather(ctx, variant, visibility != nullptr);
        const int chunk = senders_per_launch(ctx, shape_ == LtfKernelShape::Tiled, lanes(), visibility != nullptr);
        cl_mem src = in.direct;
        for (int b = 1; b <= bounces; ++b) {
            // Physical ends in `out` (the last bounce writes it); AsWritten keeps its running total there.
            cl_mem dst = physical ? ((bounces - b) % 2 == 0 ? out : ping_.get()) : (b % 2 ? ping_.get() : pong_.get());
            senders_.args(src, in.albedo, z_, int(physical), V, sender_);
            ctx.launch(senders_, 1, &global, &local);
            for (int j0 = 0; j0 < V; j0 += chunk) {
                g.args(geometry_, mid_, half_, sender_, in.normal, in.direct, visibility ? visibility : geometry_.get(),
                       V, words, j0, std::min(V, j0 + chunk), int(j0 == 0), dst);
                ctx.launch(g, 1, &lanes_global, &local);
            }
            if (physical) {
                measure(dst, src, b);
            } else {
                measure(dst, nullptr, b);
                accumulate_.args(out, dst, V);
                ctx.launch(accumulate_, 1, &global, &local);
            }
            src = dst;
        }
    }
    if (energy) {
        std::vector<float> partial(std::size_t(bounces + 1) * groups);
        ctx.read(partial_, 0, partial.size() * sizeof(float), partial.data(), "voxel LTF: energy partial sums");
        energy->assign(std::size_t(bounces + 1), 0.0);
        for (std::size_t k = 0; k < partial.size(); ++k) (*energy)[k / groups] += partial[k];
    }
}

}  // namespace ngi::detail
