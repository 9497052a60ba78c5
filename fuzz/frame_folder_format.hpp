// The input format of fuzz_frame_folder (also written by make_corpus): a list of edits to a valid base frame
// folder. Each record is [file index byte][length, 2 bytes little-endian][length bytes]: the file
// names()[index % names().size()] is replaced by the bytes, or deleted when the length is 0.
#pragma once
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

inline std::string record(std::size_t index, const std::string& content) {
    std::string r(1, char(index));
    r += char(content.size() & 0xff);
    r += char((content.size() >> 8) & 0xff);
    return r + content;
}

}  // namespace ngi::fuzz
