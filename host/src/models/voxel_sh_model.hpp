// The "voxel_sh" model family's network (seed 004, docs/MODEL_FORMAT.md "voxel_sh"): its tensors and the runner its
// front-end (models/voxel_sh_family.cpp, which also parses the config) wraps. Per occupied voxel of one scene: 10 raw
// attributes in, 27 SH coefficients out.
//
// Everything runs on the device in the planar [C, V] layout of the packed GEMM: the input standardization (a
// per-channel affine, transposing a point list on the way) and the guard, the dense layers (im2col pack + GEMM,
// bias and activation in the GEMM epilogue), the residual adds, the set pooling, and the output de-standardization
// (folded into the last layer's epilogue: y = std * (W h) + (std * b + mean)). No host round trip between layers.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "models/safetensors.hpp"
#include "ngi/model.hpp"
#include "ops/elementwise.hpp"
#include "ops/dense.hpp"
#include "ops/gemm.hpp"
#include "ops/set_pool.hpp"

namespace ngi::detail {

constexpr int kVoxelShInputs = 10;   // x, y, z, albedo rgb, emission rgb, voxel id (seed 004 Eq. 2)
constexpr int kVoxelShOutputs = 27;  // SH bands 0-2 x RGB, [3][9]
// Standardized inputs beyond +-this (a raw value some 10^6 training ranges outside it, +-Inf, FLT_MAX) are replaced
// by it, NaN by 0 (the middle of the training range), and counted (RunInfo::sanitized_inputs). Far above any real
// input, and small enough that the first layer's sums stay finite (docs/MODEL_FORMAT.md "voxel_sh"). Python reads
// it from the generated ngi._constants (ngi.voxel_sh.INPUT_BOUND, bindings/python/ngi/voxel_sh.py).
constexpr float kVoxelShInputBound = 1e6f;

// One dense layer over planar items (ops/dense.hpp, its input read in place): y = act(scale * (W x) + shift)
// (+ residual), x [in][n] with row stride n, y planar [out][n] or item-major [n][out]. W in nn.Linear's [out][in]
// layout; empty scale = 1, empty shift = 0. The shift can be replaced per call by a device buffer (the set
// network's per-scene bias); the residual (planar, as y) is added after the activation (the resnet's blocks).
class VoxelShDense {
public:
    VoxelShDense(Context& ctx, const GemmParams& p, int in, int out, const std::vector<float>& weight,
                 const std::vector<float>& scale, const std::vector<float>& shift, Act act);
    int in() const { return dense_.in(); }
    int out() const { return dense_.out(); }
    std::size_t scratch_floats(int n) const { return dense_.scratch_floats(n); }
    std::size_t weight_bytes() const { return weight_bytes_; }
    void enqueue(Context& ctx, cl_mem x, std::size_t x_off, int n, cl_mem y, std::size_t y_off, cl_mem scratch,
                 cl_mem shift = nullptr, cl_mem residual = nullptr, bool item_major = false);

private:
    Act act_;
    Dense dense_;
    Buffer scale_, shift_;
    std::size_t weight_bytes_ = 0;
};

class VoxelShRunner {
public:
    // Checks every tensor of the file against the config (names, shapes, finite values; nothing extra).
    VoxelShRunner(Context& ctx, const ModelConfig& config, const SafetensorsFile& file, const std::string& path,
                  const GemmParams& gemm);
    // Host in, host out: [V, 10] raw attributes -> [V, 27].
    Tensor run(Context& ctx, const Tensor& input, RunInfo* info);
    // Device in, device out, planar from byte 0: in [10, n], out [27, n]. The input is only read.
    void enqueue(Context& ctx, cl_mem in, cl_mem out, int n);
    int sanitized_count(Context& ctx) { return elementwise_.sanitized_count(ctx); }
    std::size_t weight_bytes() const;

private:
    // x: item i's channel c at i * item_stride + c * channel_stride floats; y: planar [27][n], or item-major
    // [n][27] with item_major.
    void forward(Context& ctx, cl_mem x, int item_stride, int channel_stride, int n, cl_mem y, bool item_major);
    void reserve(Context& ctx, int n);  // the intermediate buffers for n items

    ModelConfig::VoxelSh cfg_;
    Elementwise elementwise_;
    SetPool pool_;
    // mlp: hidden..., output. set: phi..., rho global part (pooled -> bias), rho local part, rho..., output.
    // resnet: input, blocks..., output.
    std::vector<VoxelShDense> layers_;
    Buffer in_scale_, in_shift_;
    int widest_ = 0;    // the widest layer: a_ and b_ hold widest_ x capacity_ floats
    int capacity_ = 0;  // items the buffers below hold
    Buffer std_, a_, b_, scratch_, pooled_, bias_;  // standardized input, ping-pong, packed input, set network
    Buffer raw_, out_;                              // run(): the host's point list, the planar output
};

}  // namespace ngi::detail
