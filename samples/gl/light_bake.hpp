// Static light baked on the CPU, the way an engine bakes lightmaps: per exposed face a K x K grid of texels holding
// the part of the tracer's "direct" feature that does not come from the sun (which the rasterizer shadow-maps per
// pixel): the sky over the hemisphere with visibility and the emissive blocks, in irradiance / pi.
//
//   sky      (1/pi) * integral over escaping directions of sky_radiance(w) cos dw: R deterministic cosine-weighted
//            rays per texel (a Hammersley set rotated per texel) through the voxel grid (voxel_dda.hpp);
//   emitters for every emissive face in front of the texel: its radiance x the exact form factor of the unit square
//            clipped to the texel's horizon (Lambert's polygon formula) x its visibility, the form-factor-weighted
//            share of 3 x 3 shadow rays to points on it that reach it.
// That is the expectation the tracer's depth-0 estimator (sun NEE + emitter NEE / portal NEE / continuation ray,
// MIS-combined) converges to, minus the sun. Lamps are baked apart at lamp level 1 so the shader scales them.
// Texels sit at the face's (i + 1/2) / K points, lifted 1 mm off the surface (the tracer's RAY_OFFSET).
#pragma once
#include <vector>

#include <glm/glm.hpp>

#include <ngi/render.hpp>
#include <ngi/scene.hpp>

#include "voxel_mesh.hpp"

namespace ngi_gl {

struct BakeSettings {
    int texels = 0;     // K texels per face edge; 0 = automatic (4 up to 20k faces, 2 up to 100k, else 1)
    int sky_rays = 256; // R cosine-weighted rays per texel
    int threads = 0;    // 0 = hardware concurrency
};

struct LightBake {
    int k = 1;                      // texels per face edge
    int tiles_per_row = 1;
    int width = 0, height = 0;      // atlas size in texels
    std::vector<float> sky_static;  // RGB per texel, row-major atlas: sky + non-lamp emitters
    std::vector<float> lamps;       // RGB per texel: lamp emitters at lamp level 1
    double ms = 0;                  // wall time of the bake
    long long rays = 0;
    glm::vec2 tile_origin(std::size_t face) const {
        return glm::vec2(float((face % tiles_per_row) * k), float((face / tiles_per_row) * k));
    }
};

// The most sky rays one bake may trace (faces x K^2 x R): 256 M, ~30 s at the ~8 M rays/s this bake reaches on two
// cores. Beyond it the bake refuses to start (ngi::InputError naming the product and the options) instead of
// running for minutes (issue 51: --bake-rays 65536 --bake-texels 16 ran past 60 s).
constexpr long long kMaxBakeRays = 256LL << 20;

LightBake bake_static_light(const ngi::VoxelScene& scene, const std::vector<ExposedFace>& faces,
                            const ngi::Lighting& lighting, const BakeSettings& settings);

}  // namespace ngi_gl
