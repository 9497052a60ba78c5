// Joint bilateral upsampling (kernels/jbu.cl): brings a low-resolution image (seed 002's indirect light, computed by
// the network at a quarter of the resolution) to full resolution, weighting the low-resolution taps by how well their
// geometry matches each full-resolution pixel's (normal and tangent-plane distance), Kopf et al. 2007 as seed 002
// section 5.3 uses it. Weights, defaults and why: docs/CONVENTIONS.md section 18.
#pragma once
#include <string>

#include "runtime/context.hpp"
#include "runtime/kernel_defines.hpp"

namespace ngi::detail {

// Largest tap-window radius (a 2r x 2r window); kernels/jbu.cl sizes its tap arrays with it (JBU_MAX_RADIUS).
constexpr int kJbuMaxRadius = 3;
constexpr int kJbuMaxChannels = 64;
// Image sides accepted (both resolutions).
constexpr int kJbuMaxSide = 16384;

// Output pixels of one row per work-item of jbu_upsample8, the kernel for 1 to 4 channels on PoCL's CPU devices
// (kernels/jbu_vec.cl, its own program; it says why: PoCL puts work-items in SIMD lanes only for kernels without inner loops; this kernel's
// lanes are explicit). Elsewhere the one-pixel kernel runs: GPUs and Mesa's llvmpipe put work-items in SIMD lanes
// themselves, and llvmpipe took ~65 s to build the float8 kernel (the Neural GI stability row went from 172 to 544 s
// in the rusticl stage).
constexpr int kJbuVec = 8;
constexpr int kJbuVecMaxChannels = 4;
// Floats per low-resolution texel of jbu_pack_taps' records (JBU_TAP_FLOATS).
constexpr int kJbuTapFloats = 12;
// Whether `info` is a device that runs jbu_upsample8 (PoCL on a CPU).
inline bool jbu_vector_device(const DeviceInfo& info) {
    return info.is_cpu && info.platform_name == "Portable Computing Language";
}

// The build options of kernels/jbu.cl.
inline std::string jbu_defines() {
    return join_defines({define("JBU_MAX_RADIUS", kJbuMaxRadius), define("JBU_VEC", kJbuVec),
                         define("JBU_TAP_FLOATS", kJbuTapFloats)});
}

struct JbuParams {
    // Standard deviation of the spatial Gaussian, in low-resolution pixels.
    float sigma_spatial = 0.75f;
    // Exponent of max(0, n_hi . n_lo): 32 keeps faces of different orientation apart (cos 30 deg^32 = 0.01) and
    // tolerates the small differences of smooth normals. 0 turns the normal term off.
    float normal_power = 32.0f;
    // Standard deviation of the tangent-plane distance, in world units (metres; a voxel block is 1 m): depth steps
    // of a block weigh exp(-50) and vanish, while coplanar taps weigh 1 however far away the surface is.
    float sigma_plane = 0.1f;
    // Window radius r: taps floor(q) - r + 1 ... floor(q) + r on each axis (2r x 2r), 1 <= r <= kJbuMaxRadius.
    int radius = 2;
    // Bilinear fallback when the geometric weights' sum is below this fraction of the spatial weights' sum.
    float fallback_ratio = 1e-6f;
    // Which kernel: Auto = jbu_upsample8 on jbu_vector_device()s for up to kJbuVecMaxChannels channels, else
    // jbu_upsample. Tests force either on any device (the simulators run both); the results agree to rounding.
    enum class Kernel { Auto, OnePixel, Rows8 } kernel = Kernel::Auto;
    // jbu_upsample8 only: read the taps once per work-item where its eight pixels share their tap columns (outputs
    // ~8x the input and more; same bits as the per-lane gathers). false forces the gathers (tests, A/B timing).
    bool shared_columns = true;
};

struct JbuInputs {
    int low_width = 0, low_height = 0, channels = 0;
    cl_mem low = nullptr;           // float [channels][low_height][low_width] (planar)
    cl_mem low_normal = nullptr;    // float [3][low_height][low_width]: unit normals; zero = no surface
    cl_mem low_position = nullptr;  // float [3][low_height][low_width]: world positions
    int width = 0, height = 0;      // output size
    cl_mem normal = nullptr;        // float [3][height][width]: unit normals; zero = no surface
    cl_mem position = nullptr;      // float [3][height][width]: world positions
};

class JointBilateralUpsample {
public:
    explicit JointBilateralUpsample(Context& ctx);
    // out: float [channels][height][width]. Returns the number of pixels that fell back to bilinear after one 4-byte
    // download when read_count, else -1 with nothing transferred (fallback_count() reads it later).
    int enqueue(Context& ctx, const JbuInputs& in, const JbuParams& params, cl_mem out, bool read_count = true);
    int fallback_count(Context& ctx) const;

private:
    Kernel kernel_, kernel_vec_, pack_taps_;  // jbu_upsample (any channel count); jbu_upsample8 and jbu_pack_taps
                                              // (built when first used)
    bool vector_device_ = false;
    Buffer fallbacks_, taps_;  // taps_: jbu_pack_taps' records (12 floats per low-resolution texel)
};

}  // namespace ngi::detail
