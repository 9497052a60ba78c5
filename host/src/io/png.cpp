// PNG through libpng's classic API, from and to memory. libpng reports errors by longjmp; the functions that
// call setjmp keep no C++ object with a destructor in their own frame, so the jump skips nothing, and the
// caller turns the stored message into an InputError naming the file.
#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "io/decode.hpp"
#include "base/file_util.hpp"
#include "ngi/error.hpp"
#include "ngi/host_memory.hpp"
#include "ngi/image_io.hpp"

namespace ngi {
namespace {

struct PngIo {
    const std::string* in = nullptr;  // read: the file's bytes
    std::size_t pos = 0;
    std::string* out = nullptr;       // write: the encoded file
    bool out_of_memory = false;
    char message[256] = {};           // libpng's error message
};

void on_error(png_structp png, png_const_charp msg) {
    auto* io = static_cast<PngIo*>(png_get_error_ptr(png));
    std::snprintf(io->message, sizeof io->message, "%s", msg);
    png_longjmp(png, 1);
}
void on_warning(png_structp, png_const_charp) {}  // e.g. "known incorrect sRGB profile": harmless, not printed

void on_read(png_structp png, png_bytep dst, png_size_t n) {
    auto* io = static_cast<PngIo*>(png_get_io_ptr(png));
    if (io->in->size() - io->pos < n) png_error(png, "unexpected end of file (truncated)");
    std::memcpy(dst, io->in->data() + io->pos, n);
    io->pos += n;
}

void on_write(png_structp png, png_bytep src, png_size_t n) {
    auto* io = static_cast<PngIo*>(png_get_io_ptr(png));
    try {
        io->out->append(reinterpret_cast<const char*>(src), n);
    } catch (...) {
        io->out_of_memory = true;
    }
    if (io->out_of_memory) png_error(png, "out of memory");  // outside the catch: longjmp must not leave a handler
}
void on_flush(png_structp) {}

struct Raw {
    png_uint_32 width = 0, height = 0;
    int channels = 0, bits = 0;
    std::uint64_t host_bytes = 0;  // set (and decode returns false, no longjmp) when over the host-memory limit
    std::vector<unsigned char> pixels;
    std::vector<png_bytep> rows;
};

// Deflate's best ratio is ~1032:1: an image whose rows (plus a filter byte each) need more than that from a file of
// `file_bytes` is corrupt, and is refused before its pixel buffer is allocated (a small flat allowance keeps tiny
// files of blank images legal).
constexpr std::uint64_t kMaxInflateRatio = 1032;
constexpr std::uint64_t kRawAllowance = 1ull << 24;

// Returns false when libpng reported an error (message in io.message).
bool decode(png_structp png, png_infop info, std::size_t file_bytes, Raw& raw) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_read_info(png, info);
    int bit_depth = 0, color_type = 0;
    png_get_IHDR(png, info, &raw.width, &raw.height, &bit_depth, &color_type, nullptr, nullptr, nullptr);
    if (color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
    if (color_type == PNG_COLOR_TYPE_GRAY && bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
    if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
    png_set_interlace_handling(png);  // Adam7 files: png_read_image then returns the final rows
    png_read_update_info(png, info);
    raw.channels = png_get_channels(png, info);
    raw.bits = png_get_bit_depth(png, info);
    const std::size_t row_bytes = png_get_rowbytes(png, info);
    if (std::uint64_t(row_bytes) * raw.height > (1ull << 32)) png_error(png, "image too large");
    if ((std::uint64_t(row_bytes) + 1) * raw.height > kRawAllowance + kMaxInflateRatio * file_bytes)
        png_error(png, "image size in the header is larger than the file's compressed data can hold");
    // Held at once: the file's bytes, the decoded rows and the float image. Checked here, before the rows are
    // allocated; the caller throws (no C++ exception may cross libpng's frames).
    const std::uint64_t host = std::uint64_t(file_bytes) + std::uint64_t(row_bytes) * raw.height +
                               std::uint64_t(raw.width) * raw.height * std::uint64_t(raw.channels) * sizeof(float);
    if (host > host_memory_limit()) {
        raw.host_bytes = host;
        return false;
    }
    raw.pixels.resize(row_bytes * raw.height);
    raw.rows.resize(raw.height);
    for (png_uint_32 y = 0; y < raw.height; ++y) raw.rows[y] = raw.pixels.data() + y * row_bytes;
    png_read_image(png, raw.rows.data());
    png_read_end(png, nullptr);
    return true;
}

bool encode(png_structp png, png_infop info, png_uint_32 w, png_uint_32 h, int color_type, png_bytepp rows) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_set_IHDR(png, info, w, h, 8, color_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    png_write_image(png, rows);
    png_write_end(png, nullptr);
    return true;
}

float srgb_to_linear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }
float linear_to_srgb(float c) { return c <= 0.0031308f ? c * 12.92f : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f; }

// Grey + alpha and RGBA: the last channel is alpha, which has no transfer function.
bool is_alpha(int c, int channels) { return (channels == 2 || channels == 4) && c == channels - 1; }

}  // namespace

Image read_png(const std::string& path, PngEncoding encoding) {
    return detail::decode_png(detail::read_file(path), path, encoding);
}

Image detail::decode_png(const std::string& bytes, const std::string& path, PngEncoding encoding) {
    if (bytes.size() < 8 || png_sig_cmp(reinterpret_cast<png_const_bytep>(bytes.data()), 0, 8) != 0)
        throw InputError("read " + path + ": not a PNG file (bad signature)");
    PngIo io;
    io.in = &bytes;
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &io, on_error, on_warning);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!info) {
        png_destroy_read_struct(&png, nullptr, nullptr);
        throw InputError("read " + path + ": out of memory");
    }
    png_set_read_fn(png, &io, on_read);
    Raw raw;
    bool ok = false;
    try {
        ok = decode(png, info, bytes.size(), raw);
    } catch (...) {
        png_destroy_read_struct(&png, &info, nullptr);
        throw;
    }
    png_destroy_read_struct(&png, &info, nullptr);
    if (raw.host_bytes) check_host_memory("read " + path, raw.host_bytes);  // throws: over the limit
    if (!ok) throw InputError("read " + path + ": corrupt or truncated PNG file: " + io.message);

    Image img(int(raw.width), int(raw.height), raw.channels);
    const float scale = raw.bits == 16 ? 1.0f / 65535.0f : 1.0f / 255.0f;
    for (int y = 0; y < img.height; ++y) {
        const unsigned char* row = raw.rows[y];
        for (int x = 0; x < img.width; ++x)
            for (int c = 0; c < img.channels; ++c) {
                const std::size_t i = std::size_t(x) * img.channels + c;
                const unsigned v = raw.bits == 16 ? unsigned(row[2 * i]) << 8 | row[2 * i + 1] : row[i];  // big-endian
                float f = float(v) * scale;
                if (encoding == PngEncoding::Srgb && !is_alpha(c, img.channels)) f = srgb_to_linear(f);
                img.at(c, y, x) = f;
            }
    }
    return img;
}

void write_png(const std::string& path, const Image& image, PngEncoding encoding) {
    static const int types[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                                PNG_COLOR_TYPE_RGB_ALPHA};
    if (image.channels < 1 || image.channels > 4)
        throw InputError("write " + path + ": PNG holds 1 to 4 channels, the image has " +
                         std::to_string(image.channels));
    if (image.width <= 0 || image.height <= 0 || image.data.size() != image.plane() * image.channels)
        throw InputError("write " + path + ": invalid image (" + std::to_string(image.width) + "x" +
                         std::to_string(image.height) + "x" + std::to_string(image.channels) + " with " +
                         std::to_string(image.data.size()) + " values)");
    const std::size_t row_bytes = std::size_t(image.width) * image.channels;
    std::vector<unsigned char> pixels(row_bytes * image.height);
    std::vector<png_bytep> rows(image.height);
    for (int y = 0; y < image.height; ++y) {
        rows[y] = pixels.data() + y * row_bytes;
        for (int x = 0; x < image.width; ++x)
            for (int c = 0; c < image.channels; ++c) {
                float f = image.at(c, y, x);
                f = std::isnan(f) ? 0.0f : std::clamp(f, 0.0f, 1.0f);
                if (encoding == PngEncoding::Srgb && !is_alpha(c, image.channels)) f = linear_to_srgb(f);
                rows[y][std::size_t(x) * image.channels + c] = static_cast<unsigned char>(std::lround(f * 255.0f));
            }
    }
    std::string encoded;
    PngIo io;
    io.out = &encoded;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &io, on_error, on_warning);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!info) {
        png_destroy_write_struct(&png, nullptr);
        throw InputError("write " + path + ": out of memory");
    }
    png_set_write_fn(png, &io, on_write, on_flush);
    const bool ok = encode(png, info, png_uint_32(image.width), png_uint_32(image.height), types[image.channels - 1],
                           rows.data());
    png_destroy_write_struct(&png, &info);
    if (!ok) throw InputError("write " + path + ": PNG encoding failed: " + io.message);
    detail::write_file_atomic(path, encoded);
}

}  // namespace ngi
