#include "ops/gather_image.hpp"

#include <array>
#include <cmath>
#include <string>

#include "runtime/kernel_defines.hpp"

namespace ngi::detail {

namespace {

// ngi::PixelFormat's, NormalEncoding's and DepthEncoding's codes and the no-surface depth, handed to the kernel as
// build options: the enums and kNoSurfaceDepth are their only definitions.
std::string format_defines() {
    return join_defines({define("FMT_F32", int(PixelFormat::F32)), define("FMT_F16", int(PixelFormat::F16)),
                         define("FMT_U8_UNORM", int(PixelFormat::U8Unorm)), define("FMT_U8_SRGB", int(PixelFormat::U8Srgb)),
                         define("FMT_U16_UNORM", int(PixelFormat::U16Unorm)),
                         define("FMT_S16_SNORM", int(PixelFormat::S16Snorm)),
                         define("FMT_R11G11B10F", int(PixelFormat::R11G11B10F)),
                         define("FMT_RGB10A2_UNORM", int(PixelFormat::RGB10A2Unorm)),
                         define("NORMAL_OCTAHEDRAL", int(NormalEncoding::Octahedral)),
                         define("DEPTH_PERSPECTIVE", int(DepthEncoding::Perspective)),
                         define("SKY_DEPTH", kNoSurfaceDepth)});
}

// The sRGB EOTF (IEC 61966-2-1) of the 256 codes of a U8 sRGB channel, in double and rounded once. Why a table: it
// is exact, and PoCL evaluates the kernel's scalar pow() one value at a time (~160 ns on this machine's CPU; a
// 1024 x 1024 RGB sRGB gather took ~500 ms, op_bench), while a table read costs what a U8 UNORM read does.
std::array<float, 256> srgb_table() {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) {
        const double v = i / 255.0;
        t[std::size_t(i)] = float(v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4));
    }
    return t;
}

}  // namespace

GatherImage::GatherImage(Context& ctx) : kernel_(ctx.kernel("gather_image", "gather_image", format_defines())) {
    const std::array<float, 256> t = srgb_table();
    srgb_ = ctx.alloc(sizeof t, "sRGB decode table");
    ctx.write(srgb_, 0, sizeof t, t.data(), "sRGB decode table");
}

void GatherImage::enqueue(Context& ctx, const GatherSource& src, int channels, int n, cl_mem dst, int dst_offset,
                          int dst_channel_stride, int sky_from) {
    static const std::size_t local[1] = {64};
    const glm::mat3& m = src.normal_to_world;  // column-major: m[column][row]
    const int rotate = m != glm::mat3(1.0f);
    kernel_.args(src.memory, cl_ulong(src.offset), cl_ulong(src.pixel_stride), cl_ulong(src.row_stride),
                 cl_ulong(src.channel_stride), int(src.format), channels, n, int(src.bottom_up), src.scale, src.bias,
                 srgb_, dst, dst_offset, dst_channel_stride, int(src.normal_encoding), rotate, m[0][0], m[1][0], m[2][0],
                 m[0][1], m[1][1], m[2][1], m[0][2], m[1][2], m[2][2], int(src.depth_encoding), src.near_m, src.far_m,
                 int(src.reversed_z), sky_from);
    const std::size_t global[1] = {std::size_t(n) * std::size_t(n)};
    ctx.launch(kernel_, 1, global, local);
}

}  // namespace ngi::detail
