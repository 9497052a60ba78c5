#include "models/voxel_sh_model.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <set>


namespace ngi {

void ModelConfig::VoxelSh::check_grid(int x, int y, int z) const {
    if (x != grid[0] || y != grid[1] || z != grid[2])
        throw InputError("voxel_sh model: the scene's grid is " + std::to_string(x) + "x" + std::to_string(y) + "x" +
                         std::to_string(z) + ", the model was trained on " + std::to_string(grid[0]) + "x" +
                         std::to_string(grid[1]) + "x" + std::to_string(grid[2]) +
                         " (its inputs hold absolute positions and voxel ids): use a model trained for this grid");
}

namespace detail {

// ---- one dense layer --------------------------------------------------------------------------------------

namespace {
const std::vector<float>& checked_weight(const std::vector<float>& weight, int in, int out,
                                         const std::vector<float>& scale, const std::vector<float>& shift) {
    if (weight.size() != std::size_t(in) * out || (!scale.empty() && int(scale.size()) != out) ||
        (!shift.empty() && int(shift.size()) != out))
        throw Error("voxel_sh dense layer: inconsistent sizes");
    return weight;
}
}  // namespace

VoxelShDense::VoxelShDense(Context& ctx, const GemmParams& p, int in, int out, const std::vector<float>& weight,
                           const std::vector<float>& scale, const std::vector<float>& shift, Act act)
    : act_(act), dense_(ctx, p, in, out, checked_weight(weight, in, out, scale, shift).data()) {
    scale_ = upload_floats(ctx, scale.empty() ? std::vector<float>(out, 1.0f) : scale, "voxel_sh scale");
    shift_ = upload_floats(ctx, shift.empty() ? std::vector<float>(out, 0.0f) : shift, "voxel_sh shift");
    weight_bytes_ = dense_.weight_bytes() + scale_.bytes() + shift_.bytes();
}

void VoxelShDense::enqueue(Context& ctx, cl_mem x, std::size_t x_off, int n, cl_mem y, std::size_t y_off,
                           cl_mem scratch, cl_mem shift, cl_mem residual, bool item_major) {
    const DenseOut out{y, y_off, item_major ? 1 : n, item_major ? dense_.out() : 1};
    dense_.enqueue(ctx, x, x_off, n, n, out, scale_.get(), shift ? shift : shift_.get(), act_, residual, 0, scratch, 0);
}

// ---- the runner -------------------------------------------------------------------------------------------

VoxelShRunner::VoxelShRunner(Context& ctx, const ModelConfig& config, const SafetensorsFile& file,
                             const std::string& path, const GemmParams& gemm)
    : cfg_(config.voxel_sh), elementwise_(ctx), pool_(ctx) {
    const std::string where = "load model " + path + ": ";
    std::set<std::string> used;
    auto tensor = [&](const std::string& name, int rows, int cols) -> const std::vector<float>& {
        auto t = file.tensors.find(name);
        if (t == file.tensors.end())
            throw InputError(where + "tensor '" + name + "' is missing (voxel_sh " + cfg_.architecture + ")");
        const std::vector<int> want = cols > 0 ? std::vector<int>{rows, cols} : std::vector<int>{rows};
        if (t->second.shape != want)
            throw InputError(where + "tensor '" + name + "' is " + shape_string(t->second.shape) + ", expected " +
                             shape_string(want));
        for (std::size_t i = 0; i < t->second.data.size(); ++i)
            if (!std::isfinite(t->second.data[i]))
                throw InputError(where + "tensor '" + name + "': value " + std::to_string(i) + " is not finite");
        used.insert(name);
        return t->second.data;
    };
    // Output de-standardization folded into the last layer's epilogue: y = std (W h + b) + mean.
    auto output_layer = [&](const std::string& prefix, int in) {
        const std::vector<float>& w = tensor(prefix + ".weight", kVoxelShOutputs, in);
        const std::vector<float>& b = tensor(prefix + ".bias", kVoxelShOutputs, 0);
        std::vector<float> scale(kVoxelShOutputs), shift(kVoxelShOutputs);
        for (int k = 0; k < kVoxelShOutputs; ++k) {
            scale[k] = float(cfg_.output_std[k]);
            shift[k] = float(cfg_.output_std[k] * double(b[k]) + cfg_.output_mean[k]);
            if (!std::isfinite(shift[k]))  // std up to 1e30 times a bias up to 3e38: beyond float
                throw InputError(where + "output_std[" + std::to_string(k) + "] x tensor '" + prefix + ".bias'[" +
                                 std::to_string(k) + "] + output_mean[" + std::to_string(k) +
                                 "] is not finite in float32");
        }
        layers_.emplace_back(ctx, gemm, in, kVoxelShOutputs, w, scale, shift, Act::none());
    };
    auto hidden_layer = [&](const std::string& prefix, int in, int out) {
        layers_.emplace_back(ctx, gemm, in, out, tensor(prefix + ".weight", out, in), std::vector<float>{},
                             tensor(prefix + ".bias", out, 0), Act::tanh());
    };

    int in = kVoxelShInputs;
    widest_ = kVoxelShOutputs;
    if (cfg_.architecture == "mlp") {
        for (std::size_t i = 0; i < cfg_.hidden.size(); ++i) {
            hidden_layer("layers." + std::to_string(i), in, cfg_.hidden[i]);
            in = cfg_.hidden[i];
        }
        output_layer("layers." + std::to_string(cfg_.hidden.size()), in);
    } else if (cfg_.architecture == "set") {
        for (std::size_t i = 0; i < cfg_.phi.size(); ++i) {
            hidden_layer("phi." + std::to_string(i), in, cfg_.phi[i]);
            in = cfg_.phi[i];
        }
        // rho.0 reads [h | max | mean] (3P wide). The pooled part is the same for every voxel of the scene, so
        // rho.0 = W[:, :P] h + (W[:, P:] pooled + b): the second term, one [rho0, 2P] x [2P, 1] product per
        // scene, becomes the per-scene bias of a P-wide layer (a third of the multiply-adds of the concat).
        const int p = in, r0 = cfg_.rho[0];
        const std::vector<float>& w = tensor("rho.0.weight", r0, 3 * p);
        std::vector<float> local(std::size_t(r0) * p), global(std::size_t(r0) * 2 * p);
        for (int o = 0; o < r0; ++o) {
            std::copy_n(w.begin() + std::size_t(o) * 3 * p, p, local.begin() + std::size_t(o) * p);
            std::copy_n(w.begin() + std::size_t(o) * 3 * p + p, 2 * p, global.begin() + std::size_t(o) * 2 * p);
        }
        layers_.emplace_back(ctx, gemm, 2 * p, r0, global, std::vector<float>{}, tensor("rho.0.bias", r0, 0),
                             Act::none());
        layers_.emplace_back(ctx, gemm, p, r0, local, std::vector<float>{}, std::vector<float>{}, Act::tanh());
        in = r0;
        for (std::size_t i = 1; i < cfg_.rho.size(); ++i) {
            hidden_layer("rho." + std::to_string(i), in, cfg_.rho[i]);
            in = cfg_.rho[i];
        }
        output_layer("rho." + std::to_string(cfg_.rho.size()), in);
    } else {
        hidden_layer("input", in, cfg_.width);
        for (int i = 0; i < cfg_.blocks; ++i) hidden_layer("blocks." + std::to_string(i), cfg_.width, cfg_.width);
        output_layer("output", cfg_.width);
    }
    for (const VoxelShDense& l : layers_) widest_ = std::max({widest_, l.in(), l.out()});
    for (const auto& [name, t] : file.tensors)
        if (!used.count(name))
            throw InputError(where + "tensor '" + name + "' is not part of this voxel_sh " + cfg_.architecture +
                             " network");

    // x' = s x + t with s = 2 / (hi - lo), t = -2 lo / (hi - lo) - 1 (0 and 0 for a constant channel).
    std::vector<float> s(kVoxelShInputs, 0.0f), t(kVoxelShInputs, 0.0f);
    for (int k = 0; k < kVoxelShInputs; ++k) {
        const double span = cfg_.input_hi[k] - cfg_.input_lo[k];
        if (span > 0) {
            s[k] = float(2.0 / span);
            t[k] = float(-2.0 * cfg_.input_lo[k] / span - 1.0);
        }
    }
    in_scale_ = upload_floats(ctx, s, "voxel_sh input scale");
    in_shift_ = upload_floats(ctx, t, "voxel_sh input shift");
}

std::size_t VoxelShRunner::weight_bytes() const {
    std::size_t b = in_scale_.bytes() + in_shift_.bytes();
    for (const VoxelShDense& l : layers_) b += l.weight_bytes();
    return b;
}

void VoxelShRunner::reserve(Context& ctx, int n) {
    if (n <= capacity_) return;
    // A layer over fewer items than a GEMM tile copies them into zero-padded rows here. Sized for the smallest item
    // count (scratch_floats(1) is the most any count needs), not for n: buffers only grow, and a later run with fewer
    // items than a tile (or the set network's one pooled "item") must fit in what a run with many allocated.
    std::size_t scratch = 1;
    for (const VoxelShDense& l : layers_) scratch = std::max(scratch, l.scratch_floats(1));
    // Offsets and sizes reach the kernels as int.
    if (std::size_t(widest_) * std::size_t(n) > std::size_t(INT_MAX) || scratch > std::size_t(INT_MAX))
        throw InputError("voxel_sh model: " + std::to_string(n) + " voxels are too many for one run of a network " +
                         std::to_string(widest_) + " wide (at most " + std::to_string(INT_MAX / widest_) + ")");
    const std::size_t f = sizeof(float), items = std::size_t(n);
    capacity_ = 0;  // if an allocation below throws, the next call allocates again instead of using reset buffers
    std_.reset();
    a_.reset();
    b_.reset();
    scratch_.reset();
    std_ = ctx.alloc(kVoxelShInputs * items * f, "voxel_sh standardized input");
    a_ = ctx.alloc(std::size_t(widest_) * items * f, "voxel_sh activations");
    b_ = ctx.alloc(std::size_t(widest_) * items * f, "voxel_sh activations");
    scratch_ = ctx.alloc(scratch * f, "voxel_sh packed input");
    if (cfg_.architecture == "set" && !pooled_) {
        pooled_ = ctx.alloc(2 * std::size_t(cfg_.phi.back()) * f, "voxel_sh pooled features");
        bias_ = ctx.alloc(std::size_t(cfg_.rho[0]) * f, "voxel_sh per-scene bias");
    }
    capacity_ = n;
}

void VoxelShRunner::forward(Context& ctx, cl_mem x, int item_stride, int channel_stride, int n, cl_mem y,
                            bool item_major) {
    reserve(ctx, n);
    cl_mem xs = std_.get(), a = a_.get(), b = b_.get(), scratch = scratch_.get();
    elementwise_.channel_affine(ctx, x, 0, item_stride, channel_stride, kVoxelShInputs, n, in_scale_.get(),
                                in_shift_.get(), xs, 0);
    elementwise_.sanitize(ctx, View{xs, 0, Shape{kVoxelShInputs, 1, n}}, -kVoxelShInputBound, kVoxelShInputBound);
    // Layers first .. last-1 ping-pong between a and b starting from `in`; the last writes y. Returns the buffer
    // the chain's last hidden layer wrote.
    auto chain = [&](std::size_t first, std::size_t end, cl_mem in, bool to_y) {
        for (std::size_t l = first; l < end; ++l) {
            const bool last = to_y && l + 1 == end;
            cl_mem out = last ? y : (in == a ? b : a);
            layers_[l].enqueue(ctx, in, 0, n, out, 0, scratch, nullptr, nullptr, last && item_major);
            in = out;
        }
        return in;
    };
    if (cfg_.architecture == "mlp") {
        chain(0, layers_.size(), xs, true);
    } else if (cfg_.architecture == "resnet") {
        layers_[0].enqueue(ctx, xs, 0, n, a, 0, scratch);
        cl_mem h = a, next = b;
        for (int i = 1; i <= cfg_.blocks; ++i) {  // next = h + tanh(W h + bias): the residual in the epilogue
            layers_[i].enqueue(ctx, h, 0, n, next, 0, scratch, nullptr, h);
            std::swap(h, next);
        }
        layers_.back().enqueue(ctx, h, 0, n, y, 0, scratch, nullptr, nullptr, item_major);
    } else {
        const std::size_t phis = cfg_.phi.size();
        const int p = cfg_.phi.back();
        cl_mem h = chain(0, phis, xs, false);
        cl_mem other = h == a ? b : a;
        pool_.pool_planar(ctx, h, 0, p, n, 0, n, PoolMode::Max, pooled_.get(), 0);
        pool_.pool_planar(ctx, h, 0, p, n, 0, n, PoolMode::Mean, pooled_.get(), std::size_t(p));
        layers_[phis].enqueue(ctx, pooled_.get(), 0, 1, bias_.get(), 0, scratch);              // W_g pooled + b
        layers_[phis + 1].enqueue(ctx, h, 0, n, other, 0, scratch, bias_.get());               // tanh(W_l h + that)
        chain(phis + 2, layers_.size(), other, true);
    }
}

void VoxelShRunner::enqueue(Context& ctx, cl_mem in, cl_mem out, int n) {
    if (n < 1 || n > (1 << 30)) throw InputError("voxel_sh model: " + std::to_string(n) + " voxels (1 .. 2^30)");
    forward(ctx, in, 1, n, n, out, false);
}

Tensor VoxelShRunner::run(Context& ctx, const Tensor& x, RunInfo* info) {
    const auto& s = x.shape;
    if (s.size() != 2 || s[1] != kVoxelShInputs)
        throw InputError("run model: input tensor is " + shape_string(s) +
                         ", a voxel_sh model takes [V, 10] (x, y, z, albedo rgb, emission rgb, voxel id per voxel)");
    if (x.data.size() != Tensor::element_count(s))
        throw InputError("run model: input tensor has " + std::to_string(x.data.size()) + " values for shape " +
                         shape_string(s));
    const int n = s[0];
    if (n < 1 || n > (1 << 30)) throw InputError("run model: " + std::to_string(n) + " voxels (1 .. 2^30)");
    const std::size_t in_bytes = x.data.size() * sizeof(float);
    const std::size_t out_bytes = std::size_t(kVoxelShOutputs) * std::size_t(n) * sizeof(float);
    ensure_buffer(ctx, raw_, in_bytes, "voxel_sh input");
    ensure_buffer(ctx, out_, out_bytes, "voxel_sh output");
    ctx.write(raw_, 0, in_bytes, x.data.data(), "voxel_sh input");
    // The point list is transposed on the way in by the affine, and back by the last layer's item-major store.
    forward(ctx, raw_.get(), kVoxelShInputs, 1, n, out_.get(), true);
    Tensor y({n, kVoxelShOutputs});
    ctx.read(out_, 0, out_bytes, y.data.data(), "voxel_sh output");
    if (info) {
        info->sanitized_inputs = elementwise_.sanitized_count(ctx);
        info->layers.clear();
        info->weight_bytes = weight_bytes();
        info->scratch_bytes = scratch_.bytes();
        info->arena_bytes = raw_.bytes() + out_.bytes() + std_.bytes() + a_.bytes() + b_.bytes() + pooled_.bytes() +
                            bias_.bytes();
        info->naive_bytes = info->arena_bytes;
    }
    return y;
}

}  // namespace detail
}  // namespace ngi
