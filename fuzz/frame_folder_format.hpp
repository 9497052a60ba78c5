// The input format of fuzz_frame_folder (also written by make_corpus): a list of edits to a valid base frame
// folder. Two kinds of record, told apart by the top bit of the first byte:
//   [index < 0x80][length, 2 bytes little-endian][length bytes]: the file names()[index % names().size()] is
//       replaced by the bytes, or deleted when the length is 0;
//   [0x80 | index][a][b][layout]: the file names()[index % names().size()] is replaced by an EXR image of extreme
//       values (extreme_image below): NaN, +-Inf, +-FLT_MAX, +-65504, denormals, a depth of 1e5, negative values,
//       all-zero or constant planes, mixed by a pattern. Byte mutations rarely make such values in a valid EXR.
#pragma once
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "ngi/camera.hpp"
#include "ngi/image.hpp"

namespace ngi::fuzz {

inline const std::vector<std::string>& frame_file_names() {
    static const std::vector<std::string> names = [] {
        std::vector<std::string> v = {"camera.json", "reference.exr"};
        for (int fi = 0; fi < kFeatureCount; ++fi)
            for (int k = 0; k < kFaceCount; ++k)
                for (const char* ext : {".exr", ".png"})
                    v.push_back(std::string(face_name(Face(k))) + "_" + feature_name(Feature(fi)) + ext);
        return v;
    }();
    return names;
}

// The base frame: 2x2 faces, every required feature (EXR), plausible values.
inline Frame base_frame() {
    Frame f;
    f.n = 2;
    for (int fi = 0; fi < kFeatureCount; ++fi) {
        const Feature feat = Feature(fi);
        if (feat == Feature::Emission || feat == Feature::Env) continue;  // optional: the fuzzer may add them
        for (int k = 0; k < kFaceCount; ++k) {
            Image img(2, 2, feature_channels(feat), 0.5f);
            if (feat == Feature::Normal)
                for (int p = 0; p < 4; ++p) img.data[p] = 0.0f, img.data[4 + p] = 1.0f, img.data[8 + p] = 0.0f;
            img.data[0] = 0.25f * float(k);
            f.get(feat, Face(k)) = std::move(img);
        }
    }
    return f;
}

// The values of an extreme record (a, b index this table modulo its size).
inline const std::vector<float>& extreme_values() {
    static const std::vector<float> v = {std::numeric_limits<float>::quiet_NaN(),
                                         std::numeric_limits<float>::infinity(),
                                         -std::numeric_limits<float>::infinity(),
                                         FLT_MAX, -FLT_MAX, 65504.0f, -65504.0f, 65520.0f /* rounds to half Inf */,
                                         std::numeric_limits<float>::denorm_min(), FLT_MIN / 4.0f, -FLT_MIN / 4.0f,
                                         1e5f, -1.0f, -1e-30f, 0.0f, -0.0f, 1.0f, 0.5f, 1e-8f, 1e30f};
    return v;
}

// An image described by an extreme record: n x n (layout bits 0-1: 2, 1, 3, 2; 2 is the base frame's size),
// `channels` channels plus an alpha channel if layout bit 3, values by pattern (bits 4-6): every value a;
// a checkerboard of a and b; pixel 0 b, the rest a; channel 0 b, the rest a; a b every third value; the first
// half a, the rest b; a ramp i * a; every value a except the last, b. Written as float unless layout bit 2 (half:
// finite values beyond +-65504 are clamped, NaN and Inf kept).
struct ExtremeImage {
    Image image;
    bool half = false;
};
inline ExtremeImage extreme_image(std::uint8_t a, std::uint8_t b, std::uint8_t layout, int channels) {
    const auto& t = extreme_values();
    const float va = t[a % t.size()], vb = t[b % t.size()];
    static const int sizes[4] = {2, 1, 3, 2};
    const int n = sizes[layout & 3];
    const int c = channels + ((layout >> 3) & 1);
    ExtremeImage e{Image(n, n, c), ((layout >> 2) & 1) != 0};
    const std::size_t plane = std::size_t(n) * std::size_t(n), count = plane * std::size_t(c);
    for (std::size_t i = 0; i < count; ++i) {
        const std::size_t p = i % plane, ch = i / plane, x = p % std::size_t(n), y = p / std::size_t(n);
        float v = va;
        switch ((layout >> 4) & 7) {
            case 0: break;
            case 1: v = (x + y) % 2 ? vb : va; break;
            case 2: v = p == 0 ? vb : va; break;
            case 3: v = ch == 0 ? vb : va; break;
            case 4: v = i % 3 == 2 ? vb : va; break;
            case 5: v = i < count / 2 ? va : vb; break;
            case 6: v = float(i) * va; break;
            default: v = i + 1 == count ? vb : va; break;
        }
        e.image.data[i] = v;
    }
    return e;
}

inline std::string extreme_record(std::size_t index, std::uint8_t a, std::uint8_t b, std::uint8_t layout) {
    return std::string{char(0x80 | (index & 0x7f)), char(a), char(b), char(layout)};
}

inline std::string record(std::size_t index, const std::string& content) {
    std::string r(1, char(index));
    r += char(content.size() & 0xff);
    r += char((content.size() >> 8) & 0xff);
    return r + content;
}

}  // namespace ngi::fuzz
