// The diffuse material of a block or a triangle: what the path tracer shades with. Colours are linear RGB.
#pragma once
#include <glm/glm.hpp>

namespace ngi {

// The brightest emission a scene may hold (radiance, each channel): the largest half float, which is also the
// lightmap decode's cap (docs/CONVENTIONS.md section 8). Brighter values are almost surely a unit mistake, and the
// tracer's sums must stay finite: a MATL _emit of 3e38 became Inf after the .vox flux scaling, and an Inf emitter
// lit nothing (Inf x 0 = NaN, sanitized to 0), so the reference came out black with exit 0. VoxelScene::add_material
// refuses emission beyond this bound (or not finite, or negative); the loaders name the file and the material.
inline constexpr float kMaxEmission = 65504.0f;

// A Lambertian material. Colours are linear RGB.
struct Material {
    glm::vec3 albedo{0.8f};
    glm::vec3 emission{0.0f};  // emitted radiance (same unit as the sky and the lighting buffers), all faces
    bool lamp = false;         // emission is scaled by Lighting::lamp_level (lamps switch on at dusk)
};

}  // namespace ngi
