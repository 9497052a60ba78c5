// Seed 004's voxel radiance field: the occupied surface voxels of a voxel scene with their per-voxel attributes
// (position, albedo, emission, dense id), normals and probe points, and, from the path tracer, the ground truth
// each voxel's network predicts: 27 SH coefficients (bands 0-2 x RGB) of the light it receives, plus direct and
// full lighting at its probe point and per exposed face. Definitions and units: docs/VOXEL_FIELD.md.
//
// Units as in ngi/render.hpp: every "lighting" value is irradiance / pi (what a white Lambertian surface reflects),
// radiance (SH, sky, emission) is in the same unit, so reflected radiance = albedo * lighting and the lighting of
// a surface of normal n from the SH is  (1 / pi) sum_lm A_l c_lm Y_lm(n)  (docs/CONVENTIONS.md section 14).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "ngi/device.hpp"
#include "ngi/render.hpp"
#include "ngi/scene.hpp"

namespace ngi {

// Per-voxel attributes (seed 004, Eq. 2): block centre x, y, z (metres), albedo rgb, emission rgb (lamps scaled by
// the lamp level), dense id x + X (y + Y z) as a float.
constexpr int kVoxelAttributes = 10;

// Surface voxels one call accepts: 2^20. Every voxel costs about 300 bytes of outputs on the host and as much on
// the device (27 SH + 3 + 3 + 18 lighting floats, attributes, normal, probe) and ~10^4 traced rays at the default
// settings, so 2^20 voxels are ~0.3 GB and ~10^10 rays (about an hour at the tracer's 5 Mrays/s per CPU core);
// seed 004's scenes have ~10^4.
constexpr std::size_t kMaxFieldVoxels = std::size_t(1) << 20;
// Voxels of a visibility mask: 2^15. The mask is V^2 / 8 bytes (128 MiB here, on the host and on the device) and
// V^2 / 2 segment traversals (5 * 10^8 here, minutes on a CPU).
constexpr std::size_t kMaxVisibilityVoxels = std::size_t(1) << 15;
// Blocks of a grid whose surface voxels are compacted: 2^24, so that every block id is exact as a float attribute.
constexpr std::size_t kMaxFieldGridBlocks = std::size_t(1) << 24;

struct SurfaceVoxels {
    glm::ivec3 grid{0};
    std::vector<glm::ivec3> cell;          // per surface voxel, increasing id = x + X (y + Y z)
    std::vector<float> attributes;         // [V][kVoxelAttributes]
    std::vector<glm::vec3> normal;         // Eq. 3: minus the central-difference occupancy gradient, normalized
    std::vector<glm::vec3> probe;          // where the voxel's received light is measured (metres)
    std::vector<std::uint8_t> exposed;     // bit f: face f exposed (0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z)
    std::vector<std::int32_t> index_of;    // [X * Y * Z]: compact index of the block, -1 if not a surface voxel
    std::size_t size() const { return cell.size(); }
};

// The scene's surface voxels (solid blocks with at least one face toward a non-solid block; outside the grid is
// air), compacted on the device (kernels/voxel_compact.cl: flag, prefix sum, scatter). `lighting` gives the lamp
// level of the emission attribute. Throws InputError for a scene without surface voxels, over kMaxFieldGridBlocks
// blocks or over kMaxFieldVoxels surface voxels.
SurfaceVoxels surface_voxels(const Device& device, const VoxelScene& scene, const Lighting& lighting);

struct VoxelFieldSettings {
    int directions = 1024;     // M: SH projection directions per voxel, a perfect square m * m (stratified)
    int sun_rays = 64;         // K: jittered rays over the sun's disc per voxel (its visibility)
    int point_samples = 256;   // S: lighting samples of `direct`, `lighting` and each face of `face_lighting`
    int max_bounces = 8;       // bounces of the incident radiance and of `lighting` (0: direct light only)
    int rr_start = 2;          // bounces before Russian roulette (as RenderSettings)
    std::uint32_t seed = 0;    // counter-based RNG: same seed, same bits, however the work is split
    bool sky_portals = true;   // as RenderSettings: same expectation, less noise indoors
    bool sunlit_patches = true;
    // Caps the samples (directions, sun rays, point samples) one kernel launch takes per work-item; 0 =
    // as many as the device's loop limit allows (all of them on PoCL and GPUs). Any cap gives the same bits; a cap
    // keeps single launches short (GPU watchdogs) and lets tests check that.
    int max_samples_per_launch = 0;
};

struct VoxelField {
    std::vector<float> sh;             // [V][3][9]: c_k = integral of L(w) Y_k(w) over the sphere, per channel
    std::vector<float> direct;         // [V][3]: direct lighting at the probe point (voxel normal)
    std::vector<float> lighting;       // [V][3]: full lighting (max_bounces) at the probe point (voxel normal)
    std::vector<float> face_lighting;  // [V][6][3]: full lighting averaged over each exposed face, 0 elsewhere
    double ms = 0;                     // wall time of the call (device work and read-back)
    std::uint64_t rays = 0;            // rays traced
};

// The SH projection at arbitrary points (Renderer::project_points_sh): a probe grid's bake.
struct PointSh {
    std::vector<float> sh;  // [P][3][9], as VoxelField::sh
    double ms = 0;          // wall time of the call (device work and read-back)
    std::uint64_t rays = 0; // rays traced
};

}  // namespace ngi
