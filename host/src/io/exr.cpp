// OpenEXR read/write through in-memory streams: the reader sees exactly the bytes of the file (a short file is
// reported as truncated, not as an I/O error deep inside OpenEXR), and the writer's output only reaches the
// disk through write_file_atomic, after OpenEXR has finished (its OutputFile destructor swallows errors).
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfVersion.h>
#include <half.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <set>

#include "io/decode.hpp"
#include "base/file_util.hpp"
#include "ngi/error.hpp"
#include "ngi/host_memory.hpp"
#include "ngi/image_io.hpp"

namespace ngi {
namespace {

class MemoryIStream : public Imf::IStream {
public:
    MemoryIStream(const std::string& bytes, const std::string& name) : Imf::IStream(name.c_str()), bytes_(bytes) {}
    bool read(char c[], int n) override {
        if (n < 0 || bytes_.size() - pos_ < std::size_t(n)) throw std::runtime_error("unexpected end of file (truncated)");
        std::memcpy(c, bytes_.data() + pos_, std::size_t(n));
        pos_ += std::size_t(n);
        return pos_ < bytes_.size();
    }
    std::uint64_t tellg() override { return pos_; }
    void seekg(std::uint64_t pos) override { pos_ = std::min<std::uint64_t>(pos, bytes_.size()); }

private:
    const std::string& bytes_;
    std::size_t pos_ = 0;
};

class MemoryOStream : public Imf::OStream {
public:
    MemoryOStream() : Imf::OStream("memory") {}
    void write(const char c[], int n) override {
        if (pos_ + std::size_t(n) > bytes.size()) bytes.resize(pos_ + std::size_t(n));
        std::memcpy(bytes.data() + pos_, c, std::size_t(n));
        pos_ += std::size_t(n);
    }
    std::uint64_t tellp() override { return pos_; }
    void seekp(std::uint64_t pos) override { pos_ = pos; }
    std::string bytes;

private:
    std::size_t pos_ = 0;
};

// Natural order: digit runs compare as numbers ("c2" < "c10").
bool natural_less(const std::string& a, const std::string& b) {
    std::size_t i = 0, j = 0;
    while (i < a.size() && j < b.size()) {
        if (std::isdigit((unsigned char)a[i]) && std::isdigit((unsigned char)b[j])) {
            std::size_t ie = i, je = j;
            while (ie < a.size() && std::isdigit((unsigned char)a[ie])) ++ie;
            while (je < b.size() && std::isdigit((unsigned char)b[je])) ++je;
            const std::size_t za = std::min(a.find_first_not_of('0', i), ie), zb = std::min(b.find_first_not_of('0', j), je);
            if (ie - za != je - zb) return ie - za < je - zb;  // more significant digits: larger
            if (const int c = a.compare(za, ie - za, b, zb, je - zb); c != 0) return c < 0;
            i = ie;
            j = je;
        } else {
            if (a[i] != b[j]) return a[i] < b[j];
            ++i;
            ++j;
        }
    }
    return a.size() - i < b.size() - j || (a.size() - i == b.size() - j && a < b);
}

// Channel order within a layer ("diffuse.R" is channel R of layer diffuse): R, G, B, then other names in natural
// order, then A. OpenEXR stores channels sorted by name (B, G, R), which is never the order anyone means.
bool channel_less(const std::string& a, const std::string& b) {
    const std::size_t da = a.rfind('.'), db = b.rfind('.');
    const std::string la = da == std::string::npos ? "" : a.substr(0, da);
    const std::string lb = db == std::string::npos ? "" : b.substr(0, db);
    if (la != lb) return natural_less(la, lb);
    const std::string ba = da == std::string::npos ? a : a.substr(da + 1);
    const std::string bb = db == std::string::npos ? b : b.substr(db + 1);
    auto rank = [](const std::string& s) { return s == "R" ? 0 : s == "G" ? 1 : s == "B" ? 2 : s == "A" ? 4 : 3; };
    if (rank(ba) != rank(bb)) return rank(ba) < rank(bb);
    return natural_less(ba, bb);
}

// OpenEXR trusts the sizes in a file's header: an attribute of an unknown type is allocated at its declared size
// and the chunk offset table at the data window's height before a single pixel is read, so a 100-byte file can ask
// for gigabytes. This walks the header(s) first, without allocating, and refuses sizes the file cannot back:
// an attribute longer than the rest of the file, an offset table (8 bytes per chunk) larger than the file, or more
// samples than any compression yields from a file of this size (kMaxSamplesPerByte per byte, plus a flat
// allowance for small files).
constexpr long long kMaxSamplesPerByte = 1024;  // ZIP's best ratio is ~1032:1 on bytes, i.e. ~516 half samples
constexpr long long kSampleAllowance = 1ll << 24;
constexpr long long kMaxDisplaySamples = 1ll << 26;  // 256 MiB as float

// OpenEXR reads an attribute of a known type by its type, not by the size field in front of it (a box2i is 16
// bytes, a chlist ends at its empty name, a preview is width * height pixels), so a size field that disagrees
// with the value would make OpenEXR and this walker part ways, and some values allocate by their own length
// fields (stringvector entries, previews). Every known type's value must therefore fill exactly its declared size.
template <class Bad>
void check_attribute_size(const std::string& name, const std::string& type, const char* v, std::size_t size,
                          const Bad& bad) {
    static const std::pair<const char*, std::size_t> fixed[] = {
        {"box2i", 16}, {"box2f", 16}, {"chromaticities", 32}, {"compression", 1}, {"double", 8}, {"envmap", 1},
        {"float", 4}, {"int", 4}, {"keycode", 28}, {"lineOrder", 1}, {"m33f", 36}, {"m33d", 72}, {"m44f", 64},
        {"m44d", 128}, {"rational", 8}, {"tiledesc", 9}, {"timecode", 8}, {"v2i", 8}, {"v2f", 8}, {"v2d", 16},
        {"v3i", 12}, {"v3f", 12}, {"v3d", 24}, {"deepImageState", 1}};
    auto wrong = [&] { return bad("attribute '" + name + "' of type " + type + " does not fill its " +
                                  std::to_string(size) + " bytes"); };
    for (const auto& [t, n] : fixed)
        if (type == t) {
            if (size != n) throw wrong();
            return;
        }
    if (type == "chlist") {  // (name\0, 16 bytes)*, then \0 as the last byte
        std::size_t p = 0;
        while (p < size && v[p] != '\0') {
            const void* z = std::memchr(v + p, '\0', size - p);
            if (!z) throw wrong();
            p = std::size_t(static_cast<const char*>(z) - v) + 1 + 16;
        }
        if (p != size - 1 || size == 0) throw wrong();
    } else if (type == "stringvector") {  // (int32 length, bytes)*
        std::size_t p = 0;
        while (p < size) {
            std::int32_t n = 0;
            if (size - p < 4) throw wrong();
            std::memcpy(&n, v + p, 4);
            p += 4;
            if (n < 0 || std::size_t(n) > size - p) throw wrong();
            p += std::size_t(n);
        }
    } else if (type == "floatvector") {
        if (size % 4) throw wrong();
    } else if (type == "preview") {  // uint32 width, height, then width * height RGBA bytes
        std::uint32_t wh[2] = {0, 0};
        if (size < 8) throw wrong();
        std::memcpy(wh, v, 8);
        if (std::uint64_t(wh[0]) * wh[1] * 4 != size - 8) throw wrong();
    }
}

void prescan_header(const std::string& bytes, const std::string& what) {
    auto bad = [&](const std::string& why) { return InputError(what + "corrupt OpenEXR header: " + why); };
    if (bytes.size() < 8) throw bad("truncated");
    std::uint32_t version = 0;
    std::memcpy(&version, bytes.data() + 4, 4);
    if (version & 0x800) throw InputError(what + "deep (non-image) OpenEXR files are not supported");
    const bool multipart = version & 0x1000, tiled_single = version & 0x200;
    const std::size_t name_max = version & 0x400 ? 255 : 31;
    std::size_t pos = 8;
    auto cstring = [&](const char* kind) {
        const std::size_t end = bytes.find('\0', pos);
        if (end == std::string::npos || end - pos > name_max) throw bad(std::string(kind) + " name unterminated or too long");
        std::string s = bytes.substr(pos, end - pos);
        pos = end + 1;
        return s;
    };
    const long long file_bytes = (long long)bytes.size();
    long long chunks = 0, samples = 0;
    auto check_part = [&](long long w, long long h, bool tiled, const std::uint32_t tile[2], int compression,
                          long long channels) {
        // Sizes first (w * h cannot overflow once w <= limit / h), then the chunks they make.
        const long long limit = kSampleAllowance + kMaxSamplesPerByte * file_bytes;
        if (w > limit / h || (channels && w * h > limit / channels))
            throw bad("data window " + std::to_string(w) + "x" + std::to_string(h) + " with " +
                      std::to_string(channels) + " channels is more than a " + std::to_string(file_bytes) +
                      "-byte file can hold");
        if (tiled) {
            const long long tx = std::max<long long>(tile[0], 1), ty = std::max<long long>(tile[1], 1);
            // OpenEXR allocates one tile's worth of pixels per decoder up front, whatever the data window.
            if (tx > limit / std::max<long long>(channels, 1) / ty)
                throw bad("tiles of " + std::to_string(tx) + "x" + std::to_string(ty) + " with " +
                          std::to_string(channels) + " channels are more than a " + std::to_string(file_bytes) +
                          "-byte file can hold");
            chunks += ((w + tx - 1) / tx) * ((h + ty - 1) / ty);
        } else {
            static const int lines[10] = {1, 1, 1, 16, 32, 16, 32, 32, 32, 256};
            const int per_chunk = lines[compression >= 0 && compression < 10 ? compression : 0];
            chunks += (h + per_chunk - 1) / per_chunk;
        }
        samples += w * h * std::max<long long>(channels, 1);
        if (samples > limit || chunks > file_bytes / 8)
            throw bad("the chunk offset table or the pixel data would be larger than the " +
                      std::to_string(file_bytes) + "-byte file");
    };
    for (int part = 0;; ++part) {
        if (pos >= bytes.size()) throw bad("truncated");
        if (bytes[pos] == '\0') {  // an empty header ends a multi-part file's header list
            if (!multipart || part == 0) throw bad("empty header");
            ++pos;
            break;
        }
        std::int32_t dw[4] = {0, 0, -1, -1};
        std::uint32_t tile[2] = {0, 0};
        bool tiled = tiled_single, has_dw = false;
        int compression = 0;
        long long channels = 0;
        while (true) {
            if (pos >= bytes.size()) throw bad("truncated");
            if (bytes[pos] == '\0') { ++pos; break; }
            const std::string name = cstring("attribute"), type = cstring("type");
            if (bytes.size() - pos < 4) throw bad("truncated");
            std::int32_t size = 0;
            std::memcpy(&size, bytes.data() + pos, 4);
            pos += 4;
            if (size < 0 || std::size_t(size) > bytes.size() - pos)
                throw bad("attribute '" + name + "' claims " + std::to_string(size) + " bytes, the file has " +
                          std::to_string(bytes.size() - pos) + " left");
            const char* v = bytes.data() + pos;
            check_attribute_size(name, type, v, std::size_t(size), bad);
            if (name == "dataWindow" && type == "box2i" && size == 16) { std::memcpy(dw, v, 16); has_dw = true; }
            if (name == "tiles" && type == "tiledesc" && size == 9) { std::memcpy(tile, v, 8); tiled = true; }
            if (name == "compression" && type == "compression" && size == 1) compression = (unsigned char)v[0];
            if (name == "channels" && type == "chlist") {
                // name\0, then 16 bytes (type, pLinear + reserved, xSampling, ySampling) per channel; "\0" ends it
                for (std::size_t p = 0; p < std::size_t(size) && v[p] != '\0'; ++channels) {
                    const void* z = std::memchr(v + p, '\0', std::size_t(size) - p);
                    if (!z) break;
                    p = std::size_t(static_cast<const char*>(z) - v) + 1 + 16;
                }
            }
            pos += std::size_t(size);
        }
        const long long w = (long long)dw[2] - dw[0] + 1, h = (long long)dw[3] - dw[1] + 1;
        // A missing or empty data window is left to OpenEXR, which reports it.
        if (has_dw && w > 0 && h > 0) check_part(w, h, tiled, tile, compression, channels);
        if (!multipart) break;
    }
}

}  // namespace

std::vector<std::string> exr_channel_names(int channels) {
    if (channels == 1) return {"Y"};
    if (channels == 3) return {"R", "G", "B"};
    if (channels == 4) return {"R", "G", "B", "A"};
    std::vector<std::string> names;
    for (int c = 0; c < channels; ++c) names.push_back(std::string(1, 'c').append(std::to_string(c)));
    return names;
}

Image read_exr(const std::string& path, std::vector<std::string>* channel_names) {
    return detail::decode_exr(detail::read_file(path), path, channel_names);
}

Image detail::decode_exr(const std::string& bytes, const std::string& path, std::vector<std::string>* channel_names) {
    const std::string what = "read " + path + ": ";
    if (bytes.size() < 4 || !Imf::isImfMagic(bytes.data()))
        throw InputError(what + "not an OpenEXR file (bad magic number)");
    prescan_header(bytes, what);
    Image img;
    std::vector<std::string> names;
    try {
        MemoryIStream stream(bytes, path);
        Imf::InputFile file(stream);
        const Imf::Header& h = file.header();
        const Imath::Box2i dw = h.dataWindow(), disp = h.displayWindow();
        const long long dw_w = (long long)dw.max.x - dw.min.x + 1, dw_h = (long long)dw.max.y - dw.min.y + 1;
        const long long w = (long long)disp.max.x - disp.min.x + 1, hgt = (long long)disp.max.y - disp.min.y + 1;
        for (auto it = h.channels().begin(); it != h.channels().end(); ++it) {
            if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
                throw InputError(what + "channel " + it.name() + " is subsampled; only full-resolution channels "
                                 "are supported");
            names.push_back(it.name());
        }
        if (names.empty()) throw InputError(what + "the file has no channels");
        // Again with OpenEXR's own reading of the header: the data must fit the file (prescan_header's rule).
        const long long nc = (long long)std::max<std::size_t>(names.size(), 1);
        const long long file_limit = kSampleAllowance + kMaxSamplesPerByte * (long long)bytes.size();
        if (dw_w > 0 && dw_h > 0 && dw_w > file_limit / nc / dw_h)  // divisions: no overflow on any window
            throw InputError(what + "corrupt OpenEXR header: data window " + std::to_string(dw_w) + "x" +
                             std::to_string(dw_h) + " with " + std::to_string(names.size()) +
                             " channels is more than a " + std::to_string(bytes.size()) + "-byte file can hold");
        // Refuse absurd headers before allocating (a corrupt header must not become a std::bad_alloc).
        const long long limit = 1ll << 31;
        if (w <= 0 || hgt <= 0 || dw_w <= 0 || dw_h <= 0 || w > limit / nc / hgt || dw_w > limit / nc / dw_h)
            throw InputError(what + "unsupported image size (display window " + std::to_string(w) + "x" +
                             std::to_string(hgt) + ", data window " + std::to_string(dw_w) + "x" +
                             std::to_string(dw_h) + ", " + std::to_string(names.size()) + " channels)");
        // The display window is not backed by data in the file (pixels outside the data window read as 0): beyond
        // the data window it may add up to kMaxDisplaySamples, so a 100-byte header cannot ask for gigabytes of 0s.
        const long long data_samples = dw_w * dw_h * nc;  // <= file_limit, checked above
        if (w > std::max(data_samples, kMaxDisplaySamples) / nc / hgt)
            throw InputError(what + "display window " + std::to_string(w) + "x" + std::to_string(hgt) + " with " +
                             std::to_string(names.size()) + " channels is larger than the data window (" +
                             std::to_string(dw_w) + "x" + std::to_string(dw_h) + ") and than " +
                             std::to_string(kMaxDisplaySamples) + " samples");
        std::sort(names.begin(), names.end(), channel_less);

        // Read the data window into its own planes, then copy its overlap with the display window.
        const std::size_t plane = std::size_t(dw_w) * std::size_t(dw_h);
        // Held at once: the file's bytes, the data window's planes and the display-window image.
        check_host_memory("read " + path, std::uint64_t(bytes.size()) +
                                              (std::uint64_t(plane) + std::uint64_t(w) * std::uint64_t(hgt)) *
                                                  names.size() * sizeof(float));
        std::vector<float> data(plane * names.size());
        Imf::FrameBuffer fb;
        for (std::size_t c = 0; c < names.size(); ++c) {
            // OpenEXR addresses pixel (x, y) at base + x * xStride + y * yStride with absolute coordinates, so base
            // lies (min.x + min.y * width) pixels before the plane: far outside any object for a data window that
            // starts at 10^8 (the fuzzer's find). Pointer arithmetic that leaves its object is undefined behaviour;
            // the offset is applied to the address as an unsigned integer (wrapping is defined), and OpenEXR's own
            // arithmetic brings every pixel it writes back inside the plane.
            const std::uintptr_t offset = (std::uintptr_t(std::intptr_t(dw.min.x)) +
                                           std::uintptr_t(std::intptr_t(dw.min.y)) * std::uintptr_t(dw_w)) *
                                          sizeof(float);
            char* base = reinterpret_cast<char*>(reinterpret_cast<std::uintptr_t>(data.data() + c * plane) - offset);
            fb.insert(names[c], Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * std::size_t(dw_w)));
        }
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);

        img = Image(int(w), int(hgt), int(names.size()));
        const int x0 = std::max(dw.min.x, disp.min.x), x1 = std::min(dw.max.x, disp.max.x);
        const int y0 = std::max(dw.min.y, disp.min.y), y1 = std::min(dw.max.y, disp.max.y);
        for (std::size_t c = 0; c < names.size(); ++c)
            for (int y = y0; y <= y1; ++y)
                for (int x = x0; x <= x1; ++x)
                    img.at(int(c), y - disp.min.y, x - disp.min.x) =
                        data[c * plane + std::size_t(y - dw.min.y) * std::size_t(dw_w) + std::size_t(x - dw.min.x)];
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(what + "cannot decode (corrupt, truncated or unsupported OpenEXR file): " + e.what());
    }
    if (channel_names) *channel_names = std::move(names);
    return img;
}

void write_exr(const std::string& path, const Image& image, ExrPixelType type,
               const std::vector<std::string>& channel_names) {
    const std::string what = "write " + path + ": ";
    if (image.width <= 0 || image.height <= 0 || image.channels <= 0 || image.data.size() != image.plane() * image.channels)
        throw InputError(what + "invalid image (" + std::to_string(image.width) + "x" + std::to_string(image.height) +
                         "x" + std::to_string(image.channels) + " with " + std::to_string(image.data.size()) +
                         " values)");
    // OpenEXR converts sample types when reading but not when writing: hand it halves for a half file. Imath's
    // conversion rounds to nearest but turns finite values beyond 65504 into Inf, hence the clamp.
    const bool half = type == ExrPixelType::Half;
    std::vector<Imath::half> halves;
    if (half) {
        halves.resize(image.data.size());
        for (std::size_t i = 0; i < halves.size(); ++i) {
            const float v = image.data[i];
            halves[i] = Imath::half(std::isfinite(v) ? std::clamp(v, -65504.0f, 65504.0f) : v);
        }
    }
    const std::size_t elem = half ? sizeof(Imath::half) : sizeof(float);
    const char* base = half ? reinterpret_cast<const char*>(halves.data()) : reinterpret_cast<const char*>(image.data.data());
    const std::vector<std::string> names = channel_names.empty() ? exr_channel_names(image.channels) : channel_names;
    if (names.size() != std::size_t(image.channels) ||
        std::set<std::string>(names.begin(), names.end()).size() != names.size() ||
        std::find(names.begin(), names.end(), std::string()) != names.end())
        throw InputError(what + "needs " + std::to_string(image.channels) + " distinct, non-empty channel names, got " +
                         std::to_string(names.size()));
    MemoryOStream stream;
    try {
        Imf::Header header(image.width, image.height);
        header.compression() = Imf::ZIP_COMPRESSION;
        Imf::FrameBuffer fb;
        for (int c = 0; c < image.channels; ++c) {
            header.channels().insert(names[c], Imf::Channel(half ? Imf::HALF : Imf::FLOAT));
            fb.insert(names[c], Imf::Slice(half ? Imf::HALF : Imf::FLOAT,
                                           const_cast<char*>(base + c * image.plane() * elem), elem,
                                           elem * std::size_t(image.width)));
        }
        Imf::OutputFile file(stream, header);
        file.setFrameBuffer(fb);
        file.writePixels(image.height);
    } catch (const std::exception& e) {
        throw InputError(what + "OpenEXR encoding failed: " + e.what());
    }
    detail::write_file_atomic(path, stream.bytes);
}

}  // namespace ngi
