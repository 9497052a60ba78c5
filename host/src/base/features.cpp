#include "ngi/image.hpp"

namespace ngi {

const char* feature_name(Feature f) {
    static const char* names[kFeatureCount] = {"albedo", "normal", "depth", "direct", "emission", "env"};
    return names[int(f)];
}

int feature_channels(Feature f) { return f == Feature::Depth ? 1 : 3; }

}  // namespace ngi
