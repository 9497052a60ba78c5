// Image descriptors (ngi/image_desc.hpp): names, resolved strides and the checks that keep the gather kernel's reads
// aligned and inside the memory each descriptor names.
#include "ngi/image_desc.hpp"

#include <cmath>
#include <string>

#include "ngi/error.hpp"
#include "runtime/context.hpp"

namespace ngi {

namespace {
constexpr PixelFormat kFormats[] = {PixelFormat::F32,      PixelFormat::F16,        PixelFormat::U8Unorm,
                                    PixelFormat::U8Srgb,   PixelFormat::U16Unorm,   PixelFormat::S16Snorm,
                                    PixelFormat::R11G11B10F, PixelFormat::RGB10A2Unorm};
}  // namespace

const char* pixel_format_name(PixelFormat f) {
    switch (f) {
        case PixelFormat::F32: return "f32";
        case PixelFormat::F16: return "f16";
        case PixelFormat::U8Unorm: return "u8";
        case PixelFormat::U8Srgb: return "u8_srgb";
        case PixelFormat::U16Unorm: return "u16";
        case PixelFormat::S16Snorm: return "s16";
        case PixelFormat::R11G11B10F: return "r11g11b10f";
        case PixelFormat::RGB10A2Unorm: return "rgb10a2";
    }
    return "invalid";
}

PixelFormat pixel_format_from_name(const std::string& name) {
    std::string all;
    for (PixelFormat f : kFormats) {
        if (name == pixel_format_name(f)) return f;
        all += std::string(all.empty() ? "" : ", ") + pixel_format_name(f);
    }
    throw InputError("unknown pixel format '" + name + "' (" + all + ")");
}

std::size_t pixel_format_bytes(PixelFormat f) {
    switch (f) {
        case PixelFormat::F32:
        case PixelFormat::R11G11B10F:
        case PixelFormat::RGB10A2Unorm: return 4;
        case PixelFormat::F16:
        case PixelFormat::U16Unorm:
        case PixelFormat::S16Snorm: return 2;
        case PixelFormat::U8Unorm:
        case PixelFormat::U8Srgb: return 1;
    }
    return 0;
}

int pixel_format_packed_channels(PixelFormat f) {
    return f == PixelFormat::R11G11B10F ? 3 : f == PixelFormat::RGB10A2Unorm ? 4 : 0;
}

const char* normal_encoding_name(NormalEncoding e) {
    switch (e) {
        case NormalEncoding::Xyz: return "xyz";
        case NormalEncoding::Octahedral: return "octahedral";
    }
    return "invalid";
}

const char* depth_encoding_name(DepthEncoding e) {
    switch (e) {
        case DepthEncoding::Linear: return "linear";
        case DepthEncoding::Perspective: return "perspective";
    }
    return "invalid";
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

// The bytes from `offset` to the end of the last stored channel of the last pixel; false on overflow. A packed
// format's channels share the pixel's one word (channel stride 0).
bool span(const ImageDesc& d, const Strides& s, std::size_t& out) {
    std::size_t t = s.elem;
    const std::size_t channel_steps = pixel_format_packed_channels(d.format) ? 0 : std::size_t(d.channels - 1);
    return mul_add(channel_steps, s.channel, t, t) && mul_add(std::size_t(d.width - 1), s.pixel, t, t) &&
           mul_add(std::size_t(d.height - 1), s.row, t, t) && ((out = t), true);
}

}  // namespace

ImageDesc ImageDesc::resolved() const {
    ImageDesc r = *this;
    const std::size_t elem = pixel_format_bytes(format);
    const bool packed = pixel_format_packed_channels(format) != 0;
    if (!r.channel_stride && !packed) r.channel_stride = elem;  // packed: the channels share one word (stride 0)
    if (!r.pixel_stride) r.pixel_stride = packed ? elem : std::size_t(channels > 0 ? channels : 0) * elem;
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
    const bool octahedral = d.normal_encoding == NormalEncoding::Octahedral;
    const bool perspective = d.depth_encoding == DepthEncoding::Perspective;
    if (int(d.normal_encoding) < 0 || int(d.normal_encoding) > int(NormalEncoding::Octahedral))
        throw InputError(where + ": normal encoding code " + std::to_string(int(d.normal_encoding)) + " is unknown");
    if (int(d.depth_encoding) < 0 || int(d.depth_encoding) > int(DepthEncoding::Perspective))
        throw InputError(where + ": depth encoding code " + std::to_string(int(d.depth_encoding)) + " is unknown");
    const bool rotated = d.normal_to_world != glm::mat3(1.0f);
    if ((octahedral || rotated) && feature != Feature::Normal)
        throw InputError(where + ": " + (octahedral ? "the octahedral encoding" : "a normal rotation (normal_to_world)") +
                         " applies to normals only");
    if (perspective && feature != Feature::Depth)
        throw InputError(where + ": the perspective depth encoding applies to depth only");
    const int need = octahedral ? 2 : feature_channels(feature);
    const int packed = pixel_format_packed_channels(d.format);
    if (packed && d.channels != packed)
        throw InputError(where + ": format " + pixel_format_name(d.format) + " packs " + std::to_string(packed) +
                         " channels in each pixel's word, but the descriptor says " + std::to_string(d.channels));
    if (d.channels < need || d.channels > 4)
        throw InputError(where + " has " + std::to_string(d.channels) + " channels; " +
                         (octahedral ? "an octahedral normal" : feature_name(feature)) + " needs " +
                         std::to_string(need) + " to 4 (the first " + std::to_string(need) +
                         (need == 1 ? " is" : " are") + " read)");
    if (packed && d.channel_stride)
        throw InputError(where + ": format " + pixel_format_name(d.format) +
                         " packs its channels in one word per pixel: channel_stride must be 0");
    if (feature == Feature::Depth && !perspective && d.format != PixelFormat::F32 && d.format != PixelFormat::F16)
        throw InputError(where + ": format " + pixel_format_name(d.format) +
                         " cannot hold linear depth in metres; a depth attachment in it needs the perspective "
                         "encoding with the projection's near and far planes (depth_encoding, near_m, far_m)");
    if (perspective && !(std::isfinite(d.near_m) && d.near_m > 0.0f && d.far_m > d.near_m))
        throw InputError(where + ": the perspective depth encoding needs 0 < near_m < far_m (far_m = +Inf for an "
                         "infinite far plane), got near_m " + std::to_string(d.near_m) + ", far_m " +
                         std::to_string(d.far_m));
    if (rotated)
        for (int c = 0; c < 3; ++c)
            for (int r = 0; r < 3; ++r)
                if (!std::isfinite(d.normal_to_world[c][r]))
                    throw InputError(where + ": normal_to_world has a non-finite entry");
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
    if (s.channel < elem && !packed)
        throw InputError(where + ": channel stride " + std::to_string(s.channel) + " is below one value");
    if (s.pixel < elem) throw InputError(where + ": pixel stride " + std::to_string(s.pixel) + " is below one value");
    std::size_t row_bytes = 0, image_bytes = 0;
    if (__builtin_mul_overflow(std::size_t(n), s.pixel, &row_bytes) || s.row < row_bytes)
        throw InputError(where + ": row stride " + std::to_string(s.row) + " bytes is smaller than a row of " +
                         std::to_string(n) + " pixels of " + std::to_string(s.pixel) + " bytes");
    // A pixel's channels lie inside its pixel stride (interleaved) or one whole image apart (planar); anything else
    // makes neighbouring pixels share bytes.
    const bool interleaved = packed || std::size_t(d.channels - 1) * s.channel + elem <= s.pixel;
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
