// Shared by the pipeline benchmarks: a synthetic frame with every feature present, and sizes from "64,128".
#pragma once
#include <algorithm>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "ngi/image.hpp"

namespace ngi_bench {

// Values in each feature's usual range; depth up to 2000 m (beyond the 1000 m far plane), direct up to 10.
inline ngi::Frame synthetic_frame(int n, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    ngi::Frame fr;
    fr.n = n;
    fr.look = {0.2f, -0.1f, -1.0f};
    fr.up = {0.0f, 1.0f, 0.0f};
    for (int fi = 0; fi < ngi::kFeatureCount; ++fi)
        for (int f = 0; f < ngi::kFaceCount; ++f) {
            const auto feature = ngi::Feature(fi);
            ngi::Image im(n, n, ngi::feature_channels(feature));
            const float scale = feature == ngi::Feature::Depth ? 2000.0f : feature == ngi::Feature::Direct ? 10.0f : 1.0f;
            for (auto& v : im.data) v = u(rng) * scale;
            fr.get(feature, ngi::Face(f)) = std::move(im);
        }
    return fr;
}

inline std::vector<int> parse_sizes(const std::string& s) {
    std::vector<int> out;
    std::size_t pos = 0;
    while (pos < s.size()) {
        const std::size_t end = std::min(s.find(',', pos), s.size());
        out.push_back(std::atoi(s.substr(pos, end - pos).c_str()));
        pos = end + 1;
    }
    return out;
}

}  // namespace ngi_bench
