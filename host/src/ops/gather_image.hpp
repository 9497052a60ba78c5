// One application image (an image descriptor's memory, format, strides and row order) gathered into float planes
// on the device (kernels/gather_image.cl): what lets the pipeline take an engine's render targets as they are.
#pragma once
#include <cstddef>

#include "base/surface_depth.hpp"
#include "ngi/image_desc.hpp"
#include "runtime/context.hpp"

namespace ngi::detail {

// Where the pixels are and how they are stored; strides resolved (no zero "default" left), checked by the caller
// (validate_image_desc: aligned, in bounds).
struct GatherSource {
    cl_mem memory = nullptr;
    std::size_t offset = 0, pixel_stride = 0, row_stride = 0, channel_stride = 0;
    PixelFormat format = PixelFormat::F32;
    bool bottom_up = false;
    float scale = 1.0f, bias = 0.0f;
    NormalEncoding normal_encoding = NormalEncoding::Xyz;
    glm::mat3 normal_to_world{1.0f};
    DepthEncoding depth_encoding = DepthEncoding::Linear;
    float near_m = 0.0f, far_m = 0.0f;
    bool reversed_z = false;
};

class GatherImage {
public:
    explicit GatherImage(Context& ctx);
    // The first `channels` channels of the n x n image `src` into dst: channel c of pixel p (row-major, row 0 = top)
    // at float index dst_offset + c * dst_channel_stride + p. An octahedral normal reads 2 channels and writes 3
    // (channels = 3); a perspective depth reads and writes 1.
    // sky_from >= 0: where in dst the face's depth plane was gathered (before this call, on the same queue); an
    // octahedral normal there at kNoSurfaceDepth or beyond becomes the zero vector (the map has no "no surface").
    void enqueue(Context& ctx, const GatherSource& src, int channels, int n, cl_mem dst, int dst_offset,
                 int dst_channel_stride, int sky_from = -1);

private:
    Kernel kernel_;
    Buffer srgb_;  // 256 floats: the linear value of each U8 sRGB code
};

}  // namespace ngi::detail
