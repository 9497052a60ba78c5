// Frame inputs shaped the way engines hold them: one image descriptor per face and feature, each pointing at an
// application's render target (host memory or an OpenCL buffer) with its own pixel format, channel count, byte
// offset, pixel stride and row stride, in the spirit of OpenImageDenoise's image descriptors.
//
// SurroundPipeline::enqueue / run (ngi/pipeline.hpp) gather them on the device into the frame-plane layout with
// one kernel (`gather_image`, kernels/gather_image.cl) per image: no repacking on the host. The frame-plane layout
// itself is one case: a float32 planar image is {F32, 1 channel per plane, pixel stride 4, row stride 4 N}, and a
// feature's three planes are read as three channels with pixel stride 4 and a "channel stride" of N^2 floats
// (ImageDesc::channel_stride).
#pragma once
#include <array>
#include <cstddef>
#include <string>

#include <glm/glm.hpp>

#include "ngi/camera.hpp"
#include "ngi/device_buffer.hpp"
#include "ngi/image.hpp"

namespace ngi {

// How one stored channel value is encoded. Values are converted to float, then `scale` and `bias` apply.
enum class PixelFormat : int {
    F32 = 0,      // IEEE float32
    F16 = 1,      // IEEE half (read with vload_half: no cl_khr_fp16 needed)
    U8Unorm = 2,  // uint8 / 255
    U8Srgb = 3,   // uint8 / 255 through the sRGB EOTF (albedo in an RGBA8_SRGB target; ngi reads at most 3 channels)
};
const char* pixel_format_name(PixelFormat f);                // "f32", "f16", "u8", "u8_srgb"
PixelFormat pixel_format_from_name(const std::string& name);  // throws InputError
std::size_t pixel_format_bytes(PixelFormat f);                // 4, 2, 1, 1

// One N x N image of one feature of one face.
struct ImageDesc {
    // Where the pixels are: a buffer on the pipeline's device, or host memory (exactly one of the two).
    DeviceBuffer buffer;
    const void* host = nullptr;
    std::size_t host_bytes = 0;  // bytes readable from `host` (bounds are checked against it)

    PixelFormat format = PixelFormat::F32;
    int channels = 0;               // channels stored per pixel, 1..4; the feature reads the first 3 (depth: 1)
    int width = 0, height = 0;      // must be the pipeline's N x N
    std::size_t offset = 0;         // bytes from the start of the memory to channel 0 of the first stored row's pixel 0
    std::size_t pixel_stride = 0;   // bytes between neighbouring pixels of a row; 0 = channels x format bytes
    std::size_t row_stride = 0;     // bytes between stored rows; 0 = width x pixel_stride
    std::size_t channel_stride = 0; // bytes between a pixel's channels; 0 = format bytes (interleaved). Planar
                                    // images (ngi's frame planes) set it to the plane size.
    bool bottom_up = false;         // the first stored row is the image's bottom (OpenGL's row order)
    float scale = 1.0f, bias = 0.0f;  // value = decoded x scale + bias (normals stored as n / 2 + 1/2: 2, -1)

    bool present() const { return buffer || host != nullptr; }
    // This descriptor with every 0 ("packed") stride replaced by the stride it stands for.
    ImageDesc resolved() const;
    // The bytes the image spans from `offset` on (the end of its last channel of its last pixel), with strides
    // resolved. Throws nothing; meaningful after validation.
    std::size_t span_bytes() const;
};

// A frame as a set of image descriptors, [face][feature] (Face and Feature order). Albedo, normal, depth and direct
// are required for every face the model reads (6, or the front face for a single-view model); emission and env are
// optional as a whole: present on every face read, or on none.
struct FrameInputs {
    std::array<std::array<ImageDesc, kFeatureCount>, kFaceCount> images{};
    glm::vec3 look{0, 0, -1}, up{0, 1, 0};  // the front camera (world space)

    ImageDesc& at(Face face, Feature feature) { return images[int(face)][int(feature)]; }
    const ImageDesc& at(Face face, Feature feature) const { return images[int(face)][int(feature)]; }
};

// Checks one descriptor for an N x N image of `feature`, naming the face and feature in the InputError: a buffer
// and a host pointer (or neither), a format / channel count that cannot hold the feature (channels < 3 for a colour
// or normal, < 1 for depth, > 4), width/height other than n, strides smaller than what they step over, offsets and
// strides not multiples of the format's size (OpenCL reads aligned values), a span past the end of the memory, and
// a buffer of another device than `device`.
void validate_image_desc(const ImageDesc& desc, Face face, Feature feature, int n, const Device& device);

}  // namespace ngi
