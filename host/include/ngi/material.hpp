// The diffuse material of a block or a triangle: what the path tracer shades with. Colours are linear RGB.
#pragma once
#include <glm/glm.hpp>

namespace ngi {

// A Lambertian material. Colours are linear RGB.
struct Material {
    glm::vec3 albedo{0.8f};
    glm::vec3 emission{0.0f};  // emitted radiance (same unit as the sky and the lighting buffers), all faces
    bool lamp = false;         // emission is scaled by Lighting::lamp_level (lamps switch on at dusk)
};

}  // namespace ngi
