#include "ngi/camera.hpp"

#include <cmath>

#include "ngi/error.hpp"

namespace ngi {

const char* face_name(Face f) {
    static const char* names[kFaceCount] = {"front", "back", "left", "right", "up", "down"};
    return names[int(f)];
}

Face face_from_name(const std::string& name) {
    for (int i = 0; i < kFaceCount; ++i)
        if (name == face_name(Face(i))) return Face(i);
    throw InputError("unknown face '" + name + "' (front, back, left, right, up, down)");
}

CameraCluster CameraCluster::from_look_up(glm::vec3 look, glm::vec3 up) {
    const float ll = glm::length(look);
    if (!(ll > 0.0f) || !std::isfinite(ll)) throw InputError("camera: look vector must be finite and non-zero");
    look /= ll;
    up -= glm::dot(up, look) * look;
    const float ul = glm::length(up);
    if (!(ul > 1e-6f) || !std::isfinite(ul)) throw InputError("camera: up vector must not be zero or parallel to look");
    CameraCluster c;
    c.beta = up / ul;
    c.gamma = -look;
    c.alpha = glm::cross(c.beta, c.gamma);
    return c;
}

FaceBasis cluster_face_basis(Face f) {
    switch (f) {
        case Face::Front: return {{0, 0, -1}, {1, 0, 0}, {0, 1, 0}};
        case Face::Back: return {{0, 0, 1}, {-1, 0, 0}, {0, 1, 0}};
        case Face::Left: return {{-1, 0, 0}, {0, 0, -1}, {0, 1, 0}};
        case Face::Right: return {{1, 0, 0}, {0, 0, 1}, {0, 1, 0}};
        case Face::Up: return {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}};
        case Face::Down: return {{0, -1, 0}, {1, 0, 0}, {0, 0, -1}};
    }
    throw Error("cluster_face_basis: bad face");
}

FaceBasis CameraCluster::face(Face f) const {
    const FaceBasis b = cluster_face_basis(f);
    return {to_world(b.look), to_world(b.right), to_world(b.up)};
}

glm::vec3 face_pixel_direction(const FaceBasis& b, int col, int row, int n) {
    const float u = 2.0f * (float(col) + 0.5f) / float(n) - 1.0f;
    const float v = 1.0f - 2.0f * (float(row) + 0.5f) / float(n);
    return b.look + u * b.right + v * b.up;
}

FaceSample direction_to_face(glm::vec3 d, int n) {
    const glm::vec3 a = glm::abs(d);
    Face f;
    if (a.z >= a.x && a.z >= a.y) f = d.z < 0 ? Face::Front : Face::Back;
    else if (a.x >= a.y) f = d.x < 0 ? Face::Left : Face::Right;
    else f = d.y > 0 ? Face::Up : Face::Down;
    const FaceBasis b = cluster_face_basis(f);
    const float depth = glm::dot(d, b.look);
    const float u = glm::dot(d, b.right) / depth, v = glm::dot(d, b.up) / depth;
    return {f, (u + 1.0f) * 0.5f * float(n), (1.0f - v) * 0.5f * float(n)};
}

}  // namespace ngi
