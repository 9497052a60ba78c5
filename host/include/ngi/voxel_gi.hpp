// Lighting frames from a per-voxel field (seed 004): the light-transition function (LTF) that propagates bounces
// between a scene's surface voxels, and probe shading, which lights every visible surface of a rendered face from
// the voxel behind it (its SH-27 irradiance, or a per-voxel lighting such as the LTF's). The maths and every
// convention: docs/VOXEL_LTF.md; the voxels and the SH ground truth: ngi/voxel_field.hpp, docs/VOXEL_FIELD.md.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "ngi/camera.hpp"
#include "ngi/device.hpp"
#include "ngi/image.hpp"
#include "ngi/voxel_field.hpp"

namespace ngi {

enum class LtfVariant {
    Physical,   // radiosity between voxels: both cosines, the sender's exposed area / (pi r^2), with visibility
    AsWritten,  // seed 004's Eq. 23-30: one |cosine|, a 1 / r^2 PDF normalized over receivers, no visibility
};

// What a per-voxel field holds: SH coefficients [V][3][9] of incident radiance (shaded by the cosine lobe at the
// pixel's normal), or a lighting [V][3] (irradiance / pi at the voxel, used as is).
enum class VoxelFieldKind { Sh, Lighting };

struct ShadeStats {
    long no_voxel = 0;    // surface pixels whose block (and neighbours at 0.25 m) is not a surface voxel: lit 0
    long non_finite = 0;  // pixels with NaN/Inf depth or normal: treated as sky and counted
};

// One scene's surface voxels on one device (positions = probe points, normals, albedo, exposed faces, the dense
// index grid uploaded once). Used by one thread at a time, like every ngi object made from a Device.
class VoxelGi {
public:
    VoxelGi(const Device& device, const SurfaceVoxels& voxels);
    ~VoxelGi();
    VoxelGi(VoxelGi&&) noexcept;
    VoxelGi& operator=(VoxelGi&&) noexcept;

    std::size_t voxels() const;
    glm::ivec3 grid() const;

    // The per-voxel lighting [V][3] after `bounces` (0..64) bounces starting from the direct lighting [V][3]
    // (VoxelField::direct). `visibility` (Renderer::voxel_visibility; Physical only, null = every pair visible).
    // `energy` (optional): bounces + 1 values, the luminance sum of each iterate (AsWritten) or bounce increment
    // (Physical).
    std::vector<float> ltf(const std::vector<float>& direct, int bounces, LtfVariant variant,
                           const std::vector<std::uint32_t>* visibility = nullptr,
                           std::vector<double>* energy = nullptr);

    // The lighting (3 x n x n, irradiance / pi) of face `face` of a rendered frame (its depth and normal features)
    // taken by a camera cluster centred at `camera_position`, from a per-voxel field of this scene.
    Image shade(const Frame& frame, glm::vec3 camera_position, Face face, const std::vector<float>& field,
                VoxelFieldKind kind, ShadeStats* stats = nullptr);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ngi
