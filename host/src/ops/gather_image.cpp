#include "ops/gather_image.hpp"

#include <array>
#include <cmath>
#include <string>

namespace ngi::detail {

namespace {

// ngi::PixelFormat's codes, handed to the kernel as build options: the enum is their only definition.
std::string format_defines() {
    return "-DFMT_F32=" + std::to_string(int(PixelFormat::F32)) + " -DFMT_F16=" + std::to_string(int(PixelFormat::F16)) +
           " -DFMT_U8_UNORM=" + std::to_string(int(PixelFormat::U8Unorm)) +
           " -DFMT_U8_SRGB=" + std::to_string(int(PixelFormat::U8Srgb));
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
                          int dst_channel_stride) {
    static const std::size_t local[1] = {64};
    kernel_.args(src.memory, cl_ulong(src.offset), cl_ulong(src.pixel_stride), cl_ulong(src.row_stride),
                 cl_ulong(src.channel_stride), int(src.format), channels, n, int(src.bottom_up), src.scale, src.bias,
                 srgb_, dst, dst_offset, dst_channel_stride);
    const std::size_t global[1] = {std::size_t(n) * std::size_t(n)};
    ctx.launch(kernel_, 1, global, local);
}

}  // namespace ngi::detail
