// A 3-vector as error messages print it: "(x, y, z)", shortest round-trip-free form (%g). One place, so that every
// message naming a point, a direction or a box reads the same.
#pragma once

#include <cstdio>
#include <string>

#include <glm/vec3.hpp>

namespace ngi::detail {

inline std::string vec_text(const glm::vec3& v) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "(%g, %g, %g)", double(v.x), double(v.y), double(v.z));
    return buf;
}

}  // namespace ngi::detail
