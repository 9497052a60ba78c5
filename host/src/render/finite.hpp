// Whether every component of a vector is finite: the mesh readers' check of positions and colours.
#pragma once
#include <cmath>

#include <glm/glm.hpp>

namespace ngi::detail {

inline bool finite(glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace ngi::detail
