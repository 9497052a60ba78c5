// Images side by side for the sample's comparison pictures (compare.png of `ngi lightmap` and `ngi ao`).
#pragma once
#include <vector>

#include "ngi/image.hpp"

namespace ngi_cli {

// Images of the same height and channel count, left to right.
inline ngi::Image hconcat(const std::vector<const ngi::Image*>& images) {
    ngi::Image out(0, images[0]->height, images[0]->channels);
    for (const auto* im : images) out.width += im->width;
    out.data.assign(std::size_t(out.width) * out.height * out.channels, 0.0f);
    int x0 = 0;
    for (const auto* im : images) {
        for (int c = 0; c < out.channels; ++c)
            for (int y = 0; y < out.height; ++y)
                for (int x = 0; x < im->width; ++x) out.at(c, y, x0 + x) = im->at(c, y, x);
        x0 += im->width;
    }
    return out;
}

}  // namespace ngi_cli
