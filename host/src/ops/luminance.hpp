// Rec. 709 luminance, defined once for the host (light shares, the renderer's light selection), the kernels (the
// build options LUMA_R, LUMA_G, LUMA_B behind luminance.cl's ngi_luminance()) and Python (ngi._constants, generated
// from this header at build time). Library-internal.
#pragma once
#include <string>

#include "runtime/kernel_defines.hpp"

namespace ngi::detail {

constexpr double kRec709Luma[3] = {0.2126, 0.7152, 0.0722};

inline float luminance(float r, float g, float b) {
    return float(kRec709Luma[0]) * r + float(kRec709Luma[1]) * g + float(kRec709Luma[2]) * b;
}

// The build options of a program that lists kernels/luminance.cl: the weights as float literals.
inline std::string luminance_defines() {
    return join_defines({define("LUMA_R", float(kRec709Luma[0])), define("LUMA_G", float(kRec709Luma[1])),
                         define("LUMA_B", float(kRec709Luma[2]))});
}

}  // namespace ngi::detail
