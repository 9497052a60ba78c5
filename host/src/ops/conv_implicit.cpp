#include "ops/conv_implicit.hpp"

#include <cstdlib>
#include <cstring>

#include "ops/conv.hpp"

namespace ngi::detail {

namespace {

// Fixed work-group shape (PoCL compiles one work-group function per local size).

int floor_div(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// Tiles of at most 4 rows for layers with fewer output channels than the knob set's MR (and a set with more): one
// more program per knob set, whatever Cout is (a program per Cout would be minutes of compiling on llvmpipe for the
// tests' random shapes); the 3-channel output layer wastes one row in four instead of five in eight.
constexpr int kFewRowsMr = 4;
bool cout_fits_fewer_rows(int cout, const GemmParams& p) { return cout < p.mr && p.mr > kFewRowsMr; }

// Transposed convolution, one axis: phase p of the output (o = S*q + p) reads the padded input at row
// q + t + offset(p) with kernel tap k = up_tap(p, t) = (p + P) mod S + S*(T - 1 - t), t < T = K/S; PT = T - 1 - floor(P/S) is
// the zero padding in front that keeps every offset >= 0 (docs/ARCHITECTURE.md, "Implicit-GEMM convolution").
int up_pad_front(int T, int S, int P) { return T - 1 - floor_div(P, S); }
int up_offset(int p, int T, int S, int P) { return floor_div(p + P, S) - T + 1 + up_pad_front(T, S, P); }

// KU means the same in both kernels: micro-kernel steps written out per loop iteration. gemm_conv expands a
// layer's taps when they fit in KU (at most 4): compile-time TH, TW. Otherwise runtime tap loops (TH = TW = 0),
// one program for every geometry: Mesa takes minutes per expanded program, PoCL gains 10-15% from expanding.
std::string tap_defines(int th, int tw, int ku) {
    return th * tw <= std::min(ku, 4) ? " -DTH=" + std::to_string(th) + " -DTW=" + std::to_string(tw)
                                      : " -DTH=0 -DTW=0";
}

// conv_pad applies the input activation as v >= 0 ? v : slope * v.
bool pad_supports(Act a) {
    return a.kind == Activation::None || a.kind == Activation::ReLU || a.kind == Activation::LeakyReLU;
}
float input_slope(Act a) {
    return a.kind == Activation::None ? 1.0f : a.kind == Activation::ReLU ? 0.0f : a.alpha;
}

ConvPath path_from_environment() {
    const char* e = std::getenv("NGI_CONV");
    if (!e || !*e) return ConvPath::automatic;
    if (std::strcmp(e, "implicit") == 0) return ConvPath::implicit;
    if (std::strcmp(e, "im2col") == 0) return ConvPath::im2col;
    throw InputError(std::string("NGI_CONV='") + e + "': expected 'implicit' or 'im2col'");
}

}  // namespace

std::optional<ImplicitConv> ImplicitConv::make(Context& ctx, const GemmParams& p, const ConvSpec& spec,
                                               const float* weight, bool transposed, ConvPath path) {
    const auto& g = spec.geom;
    const int S = g.stride, P = g.pad;
    if (path == ConvPath::automatic) path = path_from_environment();
    if (path == ConvPath::im2col || p.kwg > 0 || !pad_supports(spec.in_act) || g.kh % S || g.kw % S)
        return std::nullopt;
    if (transposed && (g.kh - 2 * P != S || g.kw - 2 * P != S)) return std::nullopt;
    const int th = g.kh / S, tw = g.kw / S;
    // gemm_conv runs at most C planes x (1 + TH (1 + TW)) loop iterations per work-item, plus its epilogue's (VW
    // per vector): where the driver stops loops (llvmpipe: 65,535), a layer beyond that takes the im2col path.
    const long planes = long(spec.cin) * (transposed ? 1 : S * S);
    const long iterations = planes * (1 + long(th) * (1 + tw)) + p.nr() + long(p.mr) * p.nv * (p.vw + 1);
    if (const long limit = ctx.loop_limit(); limit > 0 && iterations > limit) return std::nullopt;
    if (transposed && (up_pad_front(th, S, P) < 0 || up_pad_front(tw, S, P) < 0)) return std::nullopt;

    GemmParams p1 = p;
    // Fewer output channels than the knob set's MR rows (the U-Net's 3-channel output layer): tiles of 4 rows. With
    // MR 8 five of its eight rows were padding, and the layer took the im2col / col2im path instead (col2im alone 3.7
    // of its 4.4 ms at N = 64; docs/PERFORMANCE.md "small shapes").
    if (cout_fits_fewer_rows(spec.cout, p)) p1.mr = kFewRowsMr;
    const std::string taps = tap_defines(th, tw, p.ku);
    p1.ku = 1;  // Kpad = K: gemm_conv walks exactly C planes x TH*TW taps
    const int cin = spec.cin, cout = spec.cout;
    // Straight into pack_a's layout (Kpad = K): panel co / MR, row k, lane co % MR; each weight read once, in the
    // file's order. (A row-major copy first, then pack_a, with the tap maps evaluated per element, was a fifth of
    // `ngi lightmap`'s time for the ngf 32 rung: ~110 ms of its model load.)
    const int mr = p1.mr, panels = (cout + mr - 1) / mr;
    const int K = transposed ? cin * th * tw : cin * S * S * th * tw;
    const std::size_t phase_floats = std::size_t(panels) * K * mr;
    const std::size_t phases = transposed ? std::size_t(S) * S : 1;
    // Per kernel tap (ky, kx): its phase and its row k within a channel's block of taps; no division per weight.
    const int taps_per_channel = K / cin;
    std::vector<std::size_t> tap_phase(std::size_t(g.kh) * g.kw);
    std::vector<int> tap_k(std::size_t(g.kh) * g.kw);
    for (int ky = 0; ky < g.kh; ++ky)
        for (int kx = 0; kx < g.kw; ++kx) {
            const std::size_t i = std::size_t(ky) * g.kw + kx;
            if (!transposed) {
                // k = ((c*S + py)*S + px)*TH*TW + ty*TW + tx  <->  weight[co][c][ty*S + py][tx*S + px]
                const int py = ky % S, ty = ky / S, px = kx % S, tx = kx / S;
                tap_phase[i] = 0;
                tap_k[i] = ((py * S + px) * th + ty) * tw + tx;
            } else {
                // Phase (py, px): k = (c*TH + t)*TW + u  <->  weight[c][co][up_tap(py, t)][up_tap(px, u)]. Each
                // kernel tap belongs to one phase: ky = up_tap(py, t) has ky mod S = (py + P) mod S, t = TH-1 - ky/S.
                int py = 0, px = 0;
                while ((py + P) % S != ky % S) ++py;
                while ((px + P) % S != kx % S) ++px;
                tap_phase[i] = std::size_t(py) * S + px;
                tap_k[i] = (th - 1 - ky / S) * tw + (tw - 1 - kx / S);
            }
        }
    const std::size_t kernel_taps = std::size_t(g.kh) * g.kw;
    // The loops walk the file's weights in their stored order (PyTorch's layouts: conv2d [cout][cin][kh][kw],
    // transposed [cin][cout][kh][kw]), so the reads stream and the writes of consecutive co fill one panel's lanes.
    // With co outer for both, a transposed layer's reads strode cout * KH * KW floats (16 KiB at cout 256): a TLB
    // miss per weight, ~60 ms of the ngf 32 rung's model load.
    const std::size_t floats = phases * phase_floats;
    Buffer packed = ctx.upload_in_place(floats * sizeof(float), transposed ? "conv_transpose2d packed weights" : "conv2d packed weights",
                                        [&](void* dst) {
        float* a = static_cast<float*>(dst);
        std::fill(a, a + floats, 0.0f);  // the last panel's rows past cout
        const auto pack_one = [&](int co, int c, const float* w) {
            // row k of co's panel: lane + k * MR
            const std::size_t row0 = std::size_t(co / mr) * K * mr + co % mr + std::size_t(c) * taps_per_channel * mr;
            for (std::size_t i = 0; i < kernel_taps; ++i) a[tap_phase[i] * phase_floats + row0 + std::size_t(tap_k[i]) * mr] = w[i];
        };
        const float* w = weight;
        if (transposed) {
            for (int c = 0; c < cin; ++c)
                for (int co = 0; co < cout; ++co, w += kernel_taps) pack_one(co, c, w);
        } else {
            for (int co = 0; co < cout; ++co)
                for (int c = 0; c < cin; ++c, w += kernel_taps) pack_one(co, c, w);
        }
    });
    return ImplicitConv(ctx, p1, taps, th, tw, cout, cin, S, P, transposed, spec.in_act, std::move(packed), phase_floats);
}

ImplicitConv::ImplicitConv(Context& ctx, const GemmParams& p, const std::string& taps, int th, int tw, int cout, int cin, int stride, int pad,
                           bool transposed, Act in_act, Buffer packed, std::size_t phase_floats)
    : p_(p),
      th_(th),
      tw_(tw),
      cout_(cout),
      cin_(cin),
      stride_(stride),
      pad_(pad),
      transposed_(transposed),
      in_act_(in_act),
      pad_kernel_(ctx.kernel("im2col", "conv_pad", im2col_defines(p.nr()))),
      gemm_(ctx.kernel("gemm", "gemm_conv",
                       gemm_kernel_defines(p) + " -DIMPLICIT=1" + taps)),
      ap_(std::move(packed)),
      phase_floats_(phase_floats) {}

ImplicitConv::Layout ImplicitConv::layout(const Shape& in) const {
    const int S = stride_, P = pad_;
    Layout l{};
    if (!transposed_) {
        l.out_h = conv_out_size(in.h, th_ * S, S, P, "conv2d height");
        l.out_w = conv_out_size(in.w, tw_ * S, S, P, "conv2d width");
        l.pad_stride = S;
        l.pty = l.ptx = P;
        l.planes = cin_ * S * S;
        l.rows = l.out_h;
        l.cols = l.out_w;
        l.ph = l.out_h + th_ - 1;
        l.rs = l.out_w + tw_ - 1;
        l.b_off = {0};
        l.out_step = 1;
    } else {
        l.out_h = in.h * S;  // exact geometries only: KH - 2P = S
        l.out_w = in.w * S;
        l.pad_stride = 1;
        l.pty = up_pad_front(th_, S, P);
        l.ptx = up_pad_front(tw_, S, P);
        l.planes = cin_;
        l.rows = in.h;
        l.cols = in.w;
        l.ph = in.h + th_ - 1 + up_offset(S - 1, th_, S, P);
        l.rs = in.w + tw_ - 1 + up_offset(S - 1, tw_, S, P);
        for (int py = 0; py < S; ++py)
            for (int px = 0; px < S; ++px) {
                l.b_off.push_back(up_offset(py, th_, S, P) * l.rs + up_offset(px, tw_, S, P));
            }
        l.out_step = S;
    }
    // Tiling: whole rows of tiles where a row is at least a tile and rounding it up to tiles wastes at most 1/8
    // (row-interleaved xp, a steady stream per tile); else linear tiles over the planar grid (narrow layers).
    const int nr = p_.nr();
    const int row_tiles = (l.cols + nr - 1) / nr;
    const bool by_rows = tiles_by_rows(l.cols);
    if (by_rows) {
        l.tiles_per_row = row_tiles;
        l.tiles = l.rows * row_tiles;
        l.cs = l.rs;
        l.row = l.planes * l.rs;
    } else {
        l.tiles_per_row = 0;
        l.tiles = (l.rows * l.rs + nr - 1) / nr;
        l.cs = l.ph * l.rs;
        l.row = l.rs;
    }
    if (!l.b_off.empty() && transposed_)  // phase offsets are in rows and columns of xp
        for (std::size_t i = 0; i < l.b_off.size(); ++i) l.b_off[i] = l.b_off[i] / l.rs * l.row + l.b_off[i] % l.rs;
    // The furthest float any lane reads: the last tile's last lane, the largest phase offset, the last tap, the
    // last channel. What lies past xp must be zeroed slack.
    const std::size_t last_base = by_rows ? std::size_t(l.rows - 1) * l.row + std::size_t(row_tiles - 1) * nr
                                          : std::size_t(l.tiles - 1) * nr;
    int max_b = 0;
    for (int b : l.b_off) max_b = std::max(max_b, b);
    const std::size_t furthest = last_base + nr - 1 + max_b + std::size_t(th_ - 1) * l.row + (tw_ - 1) +
                                 std::size_t(l.planes - 1) * l.cs;
    l.floats = std::size_t(l.planes) * l.ph * l.rs;
    l.slack = furthest + 1 > l.floats ? furthest + 1 - l.floats : 0;
    return l;
}

bool ImplicitConv::tiles_by_rows(int cols) const {
    const int nr = p_.nr(), row_tiles = (cols + nr - 1) / nr;
    if (const char* e = std::getenv("NGI_CONV_TILES"); e && *e)  // experiments: "rows" or "linear" everywhere
        return std::strcmp(e, "rows") == 0;
    return cols >= nr && std::size_t(row_tiles) * nr * 8 <= std::size_t(cols) * 9;
}

bool ImplicitConv::reads_input_in_place(const Shape& in) const {
    // One tap, stride 1, no padding and nothing to apply to the input: xp would be a copy of x. gemm_conv reads x
    // itself with linear tiles, its last tile kept inside the plane (b_limit), which needs a plane of at least NR.
    // Only where the copy would have x's own layout: linear tiles (a planar copy), or a single row (interleaving one
    // row changes nothing). A row-interleaved copy of a wider image is worth its cost: Neural GI's 8 x 256 MLP over
    // 64 x 64 pixels (K up to 634) took ~1.3x the time reading its planes in place (634 planes 16 KB apart per
    // tile, a stream per plane) on PoCL.
    if (transposed_ || th_ != 1 || tw_ != 1 || stride_ != 1 || pad_ != 0 || in_act_.kind != Activation::None)
        return false;
    return std::size_t(in.h) * in.w >= std::size_t(p_.nr()) && (in.h == 1 || !tiles_by_rows(in.w)) &&
           !direct_disabled();
}

bool ImplicitConv::direct_disabled() {
    static const bool off = [] {  // experiments: NGI_CONV_DIRECT=0 keeps the copy (conv_pad) for 1 x 1 layers too
        const char* e = std::getenv("NGI_CONV_DIRECT");
        return e && std::strcmp(e, "0") == 0;
    }();
    return off;
}

std::size_t ImplicitConv::scratch_floats(const Shape& in) const {
    if (reads_input_in_place(in)) return 0;
    const Layout l = layout(in);
    return l.floats + l.slack;
}

void ImplicitConv::enqueue(Context& ctx, const View& x, const View& y, cl_mem scratch, std::size_t scratch_off,
                           cl_mem scale, cl_mem shift, Act in_act, Act out_act, std::vector<cl_event>* events) {
    const bool ev = events != nullptr;
    if (reads_input_in_place(x.shape)) {
        const int hw = x.shape.h * x.shape.w;
        const std::size_t global[2] = {std::size_t((cout_ + p_.mr - 1) / p_.mr), std::size_t((hw + p_.nr() - 1) / p_.nr())};
        const std::size_t local[2] = {std::size_t(p_.local0), std::size_t(p_.local1)};
        gemm_.args(cout_, cin_, cin_, ap_.get(), 0, x.mem, int(x.offset), hw, x.shape.w, 1, 1, 0, x.shape.h, x.shape.w,
                   y.mem, int(y.offset), hw, x.shape.w, 1, 1, scale, shift, int(out_act.kind), out_act.alpha, hw, y.mem,
                   0, 0, 0, 0, 0);
        if (cl_event e = ctx.launch(gemm_, 2, global, local, ev); ev && e) events->push_back(e);
        return;
    }
    const Layout l = layout(x.shape);
    pad_kernel_.args(x.mem, int(x.offset), x.shape.c, x.shape.h, x.shape.w, l.pad_stride, l.pty, l.ptx, l.ph, l.rs,
                     l.planes, l.cs, l.row, scratch, int(scratch_off), input_slope(in_act), int(l.floats),
                     int(l.slack));
    const bool interleaved = l.cs < l.row;  // as conv_pad decides: its fastest dimension walks xp's rows in order
    const std::size_t gp[2] = {std::size_t(interleaved ? l.planes : l.ph), std::size_t(interleaved ? l.ph : l.planes)};
    if (cl_event e = ctx.launch(pad_kernel_, 2, gp, kPadLocal, ev); ev && e) events->push_back(e);

    const int K = l.planes * th_ * tw_;
    const int y_plane = l.out_h * l.out_w;
    // Every phase in one launch (global id 2): each has its own packed A (back to back in ap_) and its own tap and
    // output offsets, which gemm_conv derives from the stride and the padding (l.b_off, and py * out_w + px). One
    // launch instead of S*S: at N = 64 the phases of a layer are 50-300 us each on PoCL, launch-bound.
    const std::size_t phases = l.b_off.size();
    const std::size_t global[3] = {std::size_t((cout_ + p_.mr - 1) / p_.mr), std::size_t(l.tiles), phases};
    const std::size_t local[3] = {std::size_t(p_.local0), std::size_t(p_.local1), 1};
    gemm_.args(cout_, l.planes, K, ap_.get(), 0, scratch, int(scratch_off), l.cs, l.row, th_, tw_,
               l.tiles_per_row, l.rows, l.cols, y.mem, int(y.offset), y_plane, l.out_w, l.out_step,
               l.out_step, scale, shift, int(out_act.kind), out_act.alpha, 0, y.mem, 0, 0,
               transposed_ ? stride_ : 0, pad_, int(phase_floats_));
    if (cl_event e = ctx.launch(gemm_, transposed_ ? 3 : 2, global, local, ev); ev && e) events->push_back(e);
}

}  // namespace ngi::detail
