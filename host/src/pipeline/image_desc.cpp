// Image descriptors (ngi/image_desc.hpp): names, resolved strides and the checks that keep the gather kernel's reads
// aligned and inside the memory each descriptor names.
#include "ngi/image_desc.hpp"

#include <cmath>
#include <string>

#include "ngi/error.hpp"
#include "runtime/context.hpp"

namespace ngi {

const char* pixel_format_name(PixelFormat f) {
    switch (f) {
        case PixelFormat::F32: return "f32";
        case PixelFormat::F16: return "f16";
        case PixelFormat::U8Unorm: return "u8";
        case PixelFormat::U8Srgb: return "u8_srgb";
    }
    return "invalid";
}

PixelFormat pixel_format_from_name(const std::string& name) {
    for (PixelFormat f : {PixelFormat::F32, PixelFormat::F16, PixelFormat::U8Unorm, PixelFormat::U8Srgb})
        if (name == pixel_format_name(f)) return f;
    throw InputError("unknown pixel format '" + name + "' (f32, f16, u8, u8_srgb)");
}

std::size_t pixel_format_bytes(PixelFormat f) {
    switch (f) {
        case PixelFormat::F32: return 4;
        case PixelFormat::F16: return 2;
        case PixelFormat::U8Unorm:
        case PixelFormat::U8Srgb: return 1;
    }
    return 0;
}

namespace {

struct Strides {
    std::size_t elem, channel, pixel, row;
};

Strides resolve(const ImageDesc& d) {
    const ImageDesc r = d.resolved();
    return {pixel_format_bytes(d.format), r.channel_stride, r.pixel_stride, r.row_stride};
}

// a * b + c without wrapping; false when it would.
bool mul_add(std::size_t a, std::size_t b, std::size_t c, std::size_t& out) {
    std::size_t m;
    return !__builtin_mul_overflow(a, b, &m) && !__builtin_add_overflow(m, c, &out);
}

// The bytes from `offset` to the end of the last stored channel of the last pixel; false on overflow.
bool span(const ImageDesc& d, const Strides& s, std::size_t& out) {
    std::size_t t = s.elem;
    return mul_add(std::size_t(d.channels - 1), s.channel, t, t) && mul_add(std::size_t(d.width - 1), s.pixel, t, t) &&
           mul_add(std::size_t(d.height - 1), s.row, t, t) && ((out = t), true);
}

}  // namespace

ImageDesc ImageDesc::resolved() const {
    ImageDesc r = *this;
    const std::size_t elem = pixel_format_bytes(format);
    if (!r.channel_stride) r.channel_stride = elem;
    if (!r.pixel_stride) r.pixel_stride = std::size_t(channels > 0 ? channels : 0) * elem;
    if (!r.row_stride) r.row_stride = std::size_t(width > 0 ? width : 0) * r.pixel_stride;
    return r;
}

std::size_t ImageDesc::span_bytes() const {
    if (channels < 1 || width < 1 || height < 1) return 0;
    std::size_t t = 0;
    return span(*this, resolve(*this), t) ? t : 0;
}

void validate_image_desc(const ImageDesc& d, Face face, Feature feature, int n, const Device& device) {
    const std::string where =
        std::string("image '") + feature_name(feature) + "' of face '" + face_name(face) + "'";
    if (!d.present()) throw InputError(where + " is missing (neither a buffer nor a host pointer)");
    if (d.buffer && d.host) throw InputError(where + " names both a buffer and a host pointer; give one");
    const std::size_t elem = pixel_format_bytes(d.format);
    if (elem == 0) throw InputError(where + ": pixel format code " + std::to_string(int(d.format)) + " is unknown");
    const int need = feature_channels(feature);
    if (d.channels < need || d.channels > 4)
        throw InputError(where + " has " + std::to_string(d.channels) + " channels; " + feature_name(feature) +
                         " needs " + std::to_string(need) + " to 4 (the first " + std::to_string(need) +
                         (need == 1 ? " is" : " are") + " read)");
    if (d.width != n || d.height != n)
        throw InputError(where + " is " + std::to_string(d.width) + "x" + std::to_string(d.height) +
                         ", but this pipeline's faces are " + std::to_string(n) + "x" + std::to_string(n));
    if (!std::isfinite(d.scale) || !std::isfinite(d.bias))
        throw InputError(where + ": scale and bias must be finite");
    const Strides s = resolve(d);
    auto aligned = [&](std::size_t v, const char* what) {
        if (v % elem)
            throw InputError(where + ": " + what + " " + std::to_string(v) + " is not a multiple of " +
                             std::to_string(elem) + " bytes (the size of a " + pixel_format_name(d.format) +
                             " value: the device reads aligned values)");
    };
    aligned(d.offset, "byte offset");
    aligned(s.channel, "channel stride");
    aligned(s.pixel, "pixel stride");
    aligned(s.row, "row stride");
    if (s.channel < elem) throw InputError(where + ": channel stride " + std::to_string(s.channel) + " is below one value");
    if (s.pixel < elem) throw InputError(where + ": pixel stride " + std::to_string(s.pixel) + " is below one value");
    std::size_t row_bytes = 0, image_bytes = 0;
    if (__builtin_mul_overflow(std::size_t(n), s.pixel, &row_bytes) || s.row < row_bytes)
        throw InputError(where + ": row stride " + std::to_string(s.row) + " bytes is smaller than a row of " +
                         std::to_string(n) + " pixels of " + std::to_string(s.pixel) + " bytes");
    // A pixel's channels lie inside its pixel stride (interleaved) or one whole image apart (planar); anything else
    // makes neighbouring pixels share bytes.
    const bool interleaved = std::size_t(d.channels - 1) * s.channel + elem <= s.pixel;
    const bool planar = !__builtin_mul_overflow(s.row, std::size_t(n), &image_bytes) && s.channel >= image_bytes;
    if (!interleaved && !planar)
        throw InputError(where + ": pixel stride " + std::to_string(s.pixel) + " bytes is smaller than the pixel (" +
                         std::to_string(d.channels) + " channels " + std::to_string(s.channel) + " bytes apart)");
    std::size_t extent = 0;
    if (!span(d, s, extent) || extent > SIZE_MAX - d.offset)
        throw InputError(where + ": its strides span more bytes than memory can hold");
    const std::size_t memory = d.buffer ? d.buffer.bytes() : d.host_bytes;
    const char* kind = d.buffer ? "buffer" : "host memory";
    if (d.offset >= memory)
        throw InputError(where + ": byte offset " + std::to_string(d.offset) + " is past the end of its " + kind +
                         " (" + std::to_string(memory) + " bytes)");
    if (d.offset + extent > memory)
        throw InputError(where + " spans bytes [" + std::to_string(d.offset) + ", " + std::to_string(d.offset + extent) +
                         ") of its " + kind + " of " + std::to_string(memory) + " bytes");
    if (d.buffer && detail::shared_context_of(d.buffer.device()) != detail::shared_context_of(device))
        throw InputError(where + ": its buffer belongs to another device than the pipeline");
}

}  // namespace ngi
