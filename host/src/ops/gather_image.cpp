#include "ops/gather_image.hpp"

#include <string>

namespace ngi::detail {

namespace {

// ngi::PixelFormat's codes, handed to the kernel as build options: the enum is their only definition.
std::string format_defines() {
    return "-DFMT_F32=" + std::to_string(int(PixelFormat::F32)) + " -DFMT_F16=" + std::to_string(int(PixelFormat::F16)) +
           " -DFMT_U8_UNORM=" + std::to_string(int(PixelFormat::U8Unorm)) +
           " -DFMT_U8_SRGB=" + std::to_string(int(PixelFormat::U8Srgb));
}

}  // namespace

GatherImage::GatherImage(Context& ctx) : kernel_(ctx.kernel("gather_image", "gather_image", format_defines())) {}

void GatherImage::enqueue(Context& ctx, const GatherSource& src, int channels, int n, cl_mem dst, int dst_offset,
                          int dst_channel_stride) {
    static const std::size_t local[1] = {64};
    kernel_.args(src.memory, cl_ulong(src.offset), cl_ulong(src.pixel_stride), cl_ulong(src.row_stride),
                 cl_ulong(src.channel_stride), int(src.format), channels, n, int(src.bottom_up), src.scale, src.bias,
                 dst, dst_offset, dst_channel_stride);
    const std::size_t global[1] = {std::size_t(n) * std::size_t(n)};
    ctx.launch(kernel_, 1, global, local);
}

}  // namespace ngi::detail
