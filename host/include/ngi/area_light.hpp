// A rectangular area light that is not a block of the voxel grid (docs/RENDERER.md "Area light"): a one-sided
// Lambertian emitter of constant radiance over a rectangle, lit by next-event estimation only.
#pragma once
#include <glm/glm.hpp>
#include <string>

namespace ngi {

// The rectangle {centre + s half_u + t half_v : s, t in [-1, 1]} (world metres), emitting radiance `radiance`
// (the lighting buffers' unit: W / sr / m^2 up to the renderer's common scale) toward the side of
// normal() = normalize(cross(half_u, half_v)); its back side emits nothing. half_u and half_v are orthogonal
// (check_area_light). It is not geometry: rays pass through it and the camera does not see it.
struct AreaLight {
    glm::vec3 centre{0.0f};
    glm::vec3 half_u{0.5f, 0.0f, 0.0f};  // half-edge vectors: the rectangle is 2 |half_u| x 2 |half_v|
    glm::vec3 half_v{0.0f, 0.0f, 0.5f};  // default: a 1 m x 1 m panel facing down (-y), a ceiling light
    glm::vec3 radiance{0.0f};            // 0 = no area light (the default)

    bool enabled() const { return radiance.r > 0.0f || radiance.g > 0.0f || radiance.b > 0.0f; }
    glm::vec3 normal() const { return glm::normalize(glm::cross(half_u, half_v)); }
    float area() const { return 4.0f * glm::length(glm::cross(half_u, half_v)); }
    bool operator==(const AreaLight&) const = default;
};

// |cos| of the angle between half_u and half_v above which they count as not orthogonal.
constexpr float kAreaLightMaxEdgeCosine = 1.0e-3f;

// Throws InputError "<operation>: area light <field> ..." naming the field and its value unless every number is
// finite, both half edges are longer than 1e-6 m, |cos(half_u, half_v)| <= kAreaLightMaxEdgeCosine and no
// radiance channel is negative. A disabled light (radiance 0) is checked the same way.
void check_area_light(const AreaLight& light, const std::string& operation);

}  // namespace ngi
