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
    F32 = 0,          // IEEE float32
    F16 = 1,          // IEEE half (read with vload_half: no cl_khr_fp16 needed)
    U8Unorm = 2,      // uint8 / 255
    U8Srgb = 3,       // uint8 / 255 through the sRGB EOTF (albedo in an RGBA8_SRGB target; ngi reads at most 3 channels)
    U16Unorm = 4,     // uint16 / 65535 (RGBA16 / D16 targets)
    S16Snorm = 5,     // int16 / 32767, -32768 read as -1 (RG16_SNORM octahedral normals)
    R11G11B10F = 6,   // packed: one 32-bit word per pixel, R bits 0-10, G 11-21 (unsigned 11-bit floats), B 22-31
                      // (unsigned 10-bit float): GL_R11F_G11F_B10F, DXGI R11G11B10_FLOAT, Vulkan B10G11R11_UFLOAT
    RGB10A2Unorm = 7, // packed: one 32-bit word per pixel, R bits 0-9, G 10-19, B 20-29 (/ 1023), A 30-31 (/ 3):
                      // GL_RGB10_A2, DXGI R10G10B10A2_UNORM, Vulkan A2B10G10R10_UNORM_PACK32
};
const char* pixel_format_name(PixelFormat f);                // "f32", "f16", "u8", "u8_srgb", "u16", "s16",
                                                             // "r11g11b10f", "rgb10a2"
PixelFormat pixel_format_from_name(const std::string& name);  // throws InputError
std::size_t pixel_format_bytes(PixelFormat f);                // a value's bytes: 4, 2, 1, 1, 2, 2; packed formats 4
int pixel_format_packed_channels(PixelFormat f);              // 3 or 4 for a packed format (one word per pixel), else 0

// How a normal image holds its normals (the feature `normal` only).
enum class NormalEncoding : int {
    Xyz = 0,         // three channels x, y, z (any length; after scale and bias)
    Octahedral = 1,  // two channels (x, y) in [-1, 1] after scale and bias: the octahedral map of a unit vector
                     // (Cigolle et al. 2014), e.g. an RG16F or RG16_SNORM target, or RG16 unorm with scale 2, bias
                     // -1. The map has no code for "no surface": where the face's depth says none (1e4 m or more,
                     // e.g. a perspective depth's cleared value) the pipeline takes the zero vector, as the tracer's.
};
// How a depth image holds its depth (the feature `depth` only).
enum class DepthEncoding : int {
    Linear = 0,       // planar depth in metres (after scale and bias): ngi's own
    Perspective = 1,  // window depth d in [0, 1] of a perspective projection (GL with glDepthRange(0, 1), D3D, Vulkan)
                      // with ImageDesc::near_m and far_m, reversed (d = 1 at near) with reversed_z: the depth
                      // attachment as rendered. d at the far plane (the cleared value) is "no surface".
};
const char* normal_encoding_name(NormalEncoding e);  // "xyz", "octahedral"
const char* depth_encoding_name(DepthEncoding e);    // "linear", "perspective"

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

    // Normals: their encoding, and the rotation that takes them to world space (world = normal_to_world * stored,
    // glm's product), e.g. the inverse of the view matrix's rotation for view-space normals; the identity for
    // world-space normals.
    NormalEncoding normal_encoding = NormalEncoding::Xyz;
    glm::mat3 normal_to_world{1.0f};
    // Depth: its encoding, and for Perspective the projection's planes in metres: 0 < near_m < far_m, far_m = +Inf
    // for an infinite far plane.
    DepthEncoding depth_encoding = DepthEncoding::Linear;
    float near_m = 0.0f, far_m = 0.0f;
    bool reversed_z = false;

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
// or an xyz normal, < 2 for an octahedral normal, < 1 for depth, > 4; a packed format's own count), an encoding the
// feature does not take (octahedral or a rotation on anything but normals, perspective on anything but depth), a
// depth the format cannot hold (unorm, snorm or packed depth without the perspective encoding's near and far), a
// projection without 0 < near < far, a rotation that is not finite, width/height other than n, strides smaller than
// what they step over, offsets and strides not multiples of the format's value size (OpenCL reads aligned values), a
// packed format with a channel stride, a span past the end of the memory, and a buffer of another device than
// `device`.
void validate_image_desc(const ImageDesc& desc, Face face, Feature feature, int n, const Device& device);

}  // namespace ngi
