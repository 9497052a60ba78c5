#include "ops/mlp.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

#include "runtime/kernel_defines.hpp"

namespace ngi::detail {

namespace {

// kernels/mlp.cl after the activation helper (kernels/activation.cl).
constexpr const char* kMlpProgram = "mlp";

// Per-layer descriptor of mlp_fused: kDescSize ints at these slots (kernels/mlp.cl D_*, from mlp_defines()).
enum DescSlot : int { kDescIn, kDescInPad, kDescOut, kDescAct, kDescW, kDescB, kDescSize };
const std::size_t kLocal1[1] = {64};
const std::size_t kEncodeLocal[2] = {64, 1};

int pad4(int x) { return (x + 3) & ~3; }

// The build options of kernels/mlp.cl: the width class, the encoding orders and the descriptor slots.
std::string mlp_defines(int max_width) {
    return join_defines({define("MAX_WIDTH", max_width),
                         define("ORDER_COMPONENT", int(FrequencyEncoding::Order::ComponentMajor)),
                         define("ORDER_BAND", int(FrequencyEncoding::Order::BandMajor)), define("D_IN", kDescIn),
                         define("D_IN_PAD", kDescInPad), define("D_OUT", kDescOut), define("D_ACT", kDescAct),
                         define("D_W", kDescW), define("D_B", kDescB), define("D_SIZE", kDescSize), activation_defines()});
}

}  // namespace

void MlpSpec::validate(const char* what) const {
    const std::string w(what);
    if (inputs < 1) throw InputError(w + ": the MLP has " + std::to_string(inputs) + " inputs");
    if (encoding.bands < 0 || encoding.bands > 24)
        throw InputError(w + ": frequency encoding bands " + std::to_string(encoding.bands) + " not in 0..24");
    if (encoding.first_exponent < -32 || encoding.first_exponent + encoding.bands > 32)
        throw InputError(w + ": frequency encoding exponents 2^" + std::to_string(encoding.first_exponent) + " .. 2^" +
                         std::to_string(encoding.first_exponent + encoding.bands - 1) + " outside 2^-32 .. 2^31");
    if (layers.empty()) throw InputError(w + ": the MLP has no layers");
    int in = encoding.width(inputs);
    for (std::size_t l = 0; l < layers.size(); ++l) {
        const DenseSpec& d = layers[l];
        const std::string where = w + ": layer " + std::to_string(l);
        if (d.in != in)
            throw InputError(where + " takes " + std::to_string(d.in) + " inputs, the previous stage gives " +
                             std::to_string(in));
        if (d.out < 1) throw InputError(where + " has " + std::to_string(d.out) + " outputs");
        if (d.weight.size() != std::size_t(d.in) * std::size_t(d.out))
            throw InputError(where + " has " + std::to_string(d.weight.size()) + " weights, expected " +
                             std::to_string(d.out) + " x " + std::to_string(d.in));
        if (!d.bias.empty() && d.bias.size() != std::size_t(d.out))
            throw InputError(where + " has " + std::to_string(d.bias.size()) + " biases, expected " +
                             std::to_string(d.out));
        for (float v : d.weight)
            if (!std::isfinite(v)) throw InputError(where + " has a non-finite weight");
        for (float v : d.bias)
            if (!std::isfinite(v)) throw InputError(where + " has a non-finite bias");
        if (int(d.act.kind) < 0 || int(d.act.kind) > int(Activation::Exp))
            throw InputError(where + ": unknown activation code " + std::to_string(int(d.act.kind)));
        in = d.out;
    }
}

// ---- fused ------------------------------------------------------------------------------------------------

long FusedMlp::loop_iterations(const MlpSpec& spec) {
    const int width = spec.encoding.width(spec.inputs);
    long n = spec.inputs + width + 1;  // load, encode, zero padding (at most MAX_WIDTH - width, bounded by it)
    n += kFusedMlpMaxWidth;
    for (const DenseSpec& d : spec.layers) n += 1 + long(d.out) * (1 + pad4(d.in) / 4) + 3;
    return n + spec.layers.back().out;
}

bool FusedMlp::fits_device(Context& ctx, const MlpSpec& spec) {
    const long limit = ctx.loop_limit();
    return limit == 0 || loop_iterations(spec) < limit;
}

int mlp_items_per_work_item(const DeviceInfo& info) {
    if (const char* e = std::getenv("NGI_MLP_VEC")) {  // tuning override: 1, 2, 4, 8 or 16
        const std::string v = e;
        if (v == "1" || v == "2" || v == "4" || v == "8" || v == "16") return std::stoi(v);
        throw InputError("NGI_MLP_VEC='" + v + "': expected 1, 2, 4, 8 or 16");
    }
    // CPUs: 16 lanes (two AVX2 registers of floats; measured on PoCL: 16x8 258 / 268 ms and 64x32 968 / 712 ms
    // with 8 / 16 lanes, 1 lane 4-8x slower: PoCL vectorizes explicit vector types, not these per-work-item
    // loops). GPUs already run work-items in SIMD lanes: 1.
    return info.is_cpu ? 16 : 1;
}

FusedMlp::FusedMlp(Context& ctx, const MlpSpec& spec, int vec) : spec_(spec) {
    spec.validate("fused MLP");
    int widest = spec.encoding.width(spec.inputs);
    for (const DenseSpec& d : spec.layers) widest = std::max({widest, d.in, d.out});
    if (widest > kFusedMlpMaxWidth)
        throw InputError("fused MLP: a layer is " + std::to_string(widest) + " wide; the fused kernel takes up to " +
                         std::to_string(kFusedMlpMaxWidth) + " (use the dense path)");
    if (!fits_device(ctx, spec))
        throw Error("fused MLP: " + std::to_string(loop_iterations(spec)) + " loop iterations per item exceed the "
                    "device's limit of " + std::to_string(ctx.loop_limit()) + " (use the dense path)");
    // One LeakyReLU slope per network (a kernel argument, not per layer): every leaky layer must share it.
    for (const DenseSpec& d : spec.layers)
        if (d.act.kind == Activation::LeakyReLU) {
            if (alpha_set_ && d.act.alpha != alpha_)
                throw InputError("fused MLP: LeakyReLU layers with different slopes (" + std::to_string(alpha_) +
                                 ", " + std::to_string(d.act.alpha) + ") are not supported; use the dense path");
            alpha_ = d.act.alpha;
            alpha_set_ = true;
        }
    max_width_ = 16;
    while (max_width_ < pad4(widest)) max_width_ *= 2;

    // Packed parameters: per layer the weights [out][pad4(in)] (zero padded) then the bias.
    std::vector<float> params;
    std::vector<int> desc;
    for (const DenseSpec& d : spec.layers) {
        const int in_pad = pad4(d.in);
        const int w_off = int(params.size());
        params.resize(params.size() + std::size_t(d.out) * in_pad, 0.0f);
        for (int o = 0; o < d.out; ++o)
            std::copy_n(&d.weight[std::size_t(o) * d.in], d.in, &params[w_off + std::size_t(o) * in_pad]);
        const int b_off = int(params.size());
        if (d.bias.empty()) params.resize(params.size() + d.out, 0.0f);
        else params.insert(params.end(), d.bias.begin(), d.bias.end());
        int slots[kDescSize];
        slots[kDescIn] = d.in;
        slots[kDescInPad] = in_pad;
        slots[kDescOut] = d.out;
        slots[kDescAct] = int(d.act.kind);
        slots[kDescW] = w_off;
        slots[kDescB] = b_off;
        desc.insert(desc.end(), slots, slots + kDescSize);
    }
    // Constant memory when both arrays fit the device's constant buffer and argument limits.
    cl_ulong const_bytes = 0;
    cl_uint const_args = 0;
    check(clGetDeviceInfo(ctx.device(), CL_DEVICE_MAX_CONSTANT_BUFFER_SIZE, sizeof const_bytes, &const_bytes, nullptr),
          "fused MLP: query constant memory", "clGetDeviceInfo");
    check(clGetDeviceInfo(ctx.device(), CL_DEVICE_MAX_CONSTANT_ARGS, sizeof const_args, &const_args, nullptr),
          "fused MLP: query constant memory", "clGetDeviceInfo");
    const std::size_t bytes = params.size() * sizeof(float) + desc.size() * sizeof(int);
    constant_ = const_args >= 2 && bytes <= const_bytes;
    const std::string space = constant_ ? " -DPARAMS_SPACE=__constant" : " -DPARAMS_SPACE=__global";
    long macs = 0;
    for (const DenseSpec& d : spec.layers) macs += long(d.in) * d.out;
    static_arch_ = spec.encoding.bands == 0 && spec.layers.size() <= kStaticMlpMaxLayers && macs <= kStaticMlpMaxMacs;
    if (static_arch_) {  // the architecture as compile-time constants (kernels/mlp.cl mlp_static)
        std::string arch = " -DNL=" + std::to_string(spec.layers.size()) + " -DW0=" + std::to_string(spec.inputs);
        for (std::size_t l = 0; l < spec.layers.size(); ++l) {
            const std::string k = std::to_string(l + 1);
            arch += " -DW" + k + "=" + std::to_string(spec.layers[l].out) + " -DA" + k + "=" +
                    std::to_string(int(spec.layers[l].act.kind)) + " -DINPAD" + k + "=" + std::to_string(desc[kDescSize * l + kDescInPad]) +
                    " -DWOFF" + k + "=" + std::to_string(desc[kDescSize * l + kDescW]) + " -DBOFF" + k + "=" + std::to_string(desc[kDescSize * l + kDescB]);
        }
        if (vec != 0 && vec != 1 && vec != 2 && vec != 4 && vec != 8 && vec != 16)
            throw InputError("fused MLP: " + std::to_string(vec) + " items per work-item; expected 1, 2, 4, 8 or 16");
        vec_ = vec ? vec : mlp_items_per_work_item(ctx.info());
        kernel_ = ctx.kernel(kMlpProgram, "mlp_static",
                             mlp_defines(max_width_) + space + arch + " -DVEC=" + std::to_string(vec_));
    } else {
        kernel_ = ctx.kernel(kMlpProgram, "mlp_fused", mlp_defines(max_width_) + space);
    }
    params_ = ctx.alloc(params.size() * sizeof(float), "fused MLP weights");
    ctx.write(params_, 0, params.size() * sizeof(float), params.data(), "fused MLP weights");
    desc_ = ctx.alloc(desc.size() * sizeof(int), "fused MLP layers");
    ctx.write(desc_, 0, desc.size() * sizeof(int), desc.data(), "fused MLP layers");
}

cl_event FusedMlp::enqueue(Context& ctx, cl_mem x, std::size_t x_off, ItemLayout in, int n, cl_mem y,
                           std::size_t y_off, ItemLayout out, bool want_event) {
    if (n <= 0) return nullptr;
    const FrequencyEncoding& e = spec_.encoding;
    if (static_arch_)
        kernel_.args(x, int(x_off), n, in.item_stride, in.channel_stride, params_, alpha_, y, int(y_off), out.item_stride,
                     out.channel_stride);
    else
            kernel_.args(x, int(x_off), n, spec_.inputs, in.item_stride, in.channel_stride, params_, desc_, int(spec_.layers.size()),
                     e.bands, e.first_exponent, int(e.pi), int(e.include_input), int(e.order), alpha_, y, int(y_off), out.item_stride,
                     out.channel_stride);
    const std::size_t g[1] = {(std::size_t(n) + vec_ - 1) / vec_};
    return ctx.launch(kernel_, 1, g, kLocal1, want_event);
}

// ---- the encoding alone ---------------------------------------------------------------------------------------

FrequencyEncodePlanar::FrequencyEncodePlanar(Context& ctx, int inputs, const FrequencyEncoding& encoding, int vec)
    : inputs_(inputs), encoding_(encoding), vec_(vec ? vec : mlp_items_per_work_item(ctx.info())),
      kernel_(ctx.kernel(kMlpProgram, "frequency_encode_planar", mlp_defines(16) + " -DENC_VEC=" + std::to_string(vec_))) {}

cl_event FrequencyEncodePlanar::enqueue(Context& ctx, cl_mem x, std::size_t x_off, cl_mem y, std::size_t y_off, int n,
                                        bool want_event) {
    const FrequencyEncoding& e = encoding_;
    if (double(width()) * n > 2147483647.0 || x_off > 2147483647u || y_off > 2147483647u)
        throw InputError("frequency encoding: " + std::to_string(n) + " items x " + std::to_string(width()) +
                         " features exceed the kernel's 32-bit indexing");
    kernel_.args(x, int(x_off), n, inputs_, n, e.bands, e.first_exponent, int(e.pi), int(e.include_input),
                 int(e.order), y, int(y_off));
    const std::size_t g[2] = {(std::size_t(n) + vec_ - 1) / vec_, std::size_t(width())};
    return ctx.launch(kernel_, 2, g, kEncodeLocal, want_event);
}

// ---- dense ------------------------------------------------------------------------------------------------

DenseMlp::DenseMlp(Context& ctx, const GemmParams& p, const MlpSpec& spec)
    : spec_(spec), encode_(ctx, spec.inputs, spec.encoding) {
    spec.validate("dense MLP");
    layers_.reserve(spec.layers.size());
    for (const DenseSpec& d : spec.layers) {
        ConvSpec c;
        c.cin = d.in;
        c.cout = d.out;
        c.geom = {1, 1, 1, 0};
        c.out_act = d.act;
        ChannelAffine affine;
        affine.shift = d.bias;
        layers_.emplace_back(ctx, p, c, d.weight.data(), affine);
    }
}

std::size_t DenseMlp::scratch_floats(int n) const {
    std::size_t widest = 0, conv = 0;
    for (std::size_t l = 0; l < layers_.size(); ++l) {
        const DenseSpec& d = spec_.layers[l];
        widest = std::max(widest, std::size_t(d.out));
        conv = std::max(conv, layers_[l].scratch_floats(Shape{d.in, 1, n}));
    }
    return std::size_t(spec_.encoding.width(spec_.inputs)) * n + 2 * widest * n + conv;
}

void DenseMlp::enqueue(Context& ctx, const View& x, const View& y, cl_mem scratch, std::vector<cl_event>* events) {
    const int n = x.shape.h * x.shape.w;
    if (x.shape.c != spec_.inputs)
        throw InputError("dense MLP: the input has " + std::to_string(x.shape.c) + " channels, the MLP takes " +
                         std::to_string(spec_.inputs));
    const FrequencyEncoding& e = spec_.encoding;
    const std::size_t enc = std::size_t(e.width(spec_.inputs)) * n;
    std::size_t widest = 0;
    for (const DenseSpec& d : spec_.layers) widest = std::max(widest, std::size_t(d.out));
    const std::size_t act0 = enc, act1 = enc + widest * n, conv = enc + 2 * widest * n;

    View in = x;
    in.shape = Shape{x.shape.c, 1, n};
    if (e.bands > 0) {
        cl_event ev = encode_.enqueue(ctx, x.mem, x.offset, scratch, 0, n, events != nullptr);
        if (events && ev) events->push_back(ev);
        in = View{scratch, 0, Shape{e.width(spec_.inputs), 1, n}};
    }
    for (std::size_t l = 0; l < layers_.size(); ++l) {
        const bool last = l + 1 == layers_.size();
        View out = last ? View{y.mem, y.offset, Shape{spec_.layers[l].out, 1, n}}
                        : View{scratch, (l % 2 == 0) ? act0 : act1, Shape{spec_.layers[l].out, 1, n}};
        layers_[l].enqueue(ctx, in, out, scratch, conv, events);
        in = out;
    }
}

}  // namespace ngi::detail
