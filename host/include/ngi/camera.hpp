// The camera cluster of the surround-aware pipeline: six 90-degree square cameras sharing one centre, defined
// from the front camera's look and up vectors. One source of truth for the renderer, the merge and the tests;
// docs/CONVENTIONS.md explains it with pictures in words.
#pragma once
#include <array>
#include <glm/glm.hpp>
#include <string>

namespace ngi {

enum class Face : int { Front = 0, Back = 1, Left = 2, Right = 3, Up = 4, Down = 5 };
constexpr int kFaceCount = 6;
const char* face_name(Face f);  // "front", "back", "left", "right", "up", "down" (frame-folder file names)
Face face_from_name(const std::string& name);  // throws InputError

// Orthonormal camera basis of one face, in world space. right x up = -look (right-handed, OpenGL-style camera).
struct FaceBasis {
    glm::vec3 look, right, up;
};

// Cluster space: alpha = beta x gamma (right), beta = up, gamma = -look (backward) of the front camera.
// The thesis's normal transform S = [alpha; beta; gamma] maps world vectors into this space.
struct CameraCluster {
    glm::vec3 alpha, beta, gamma;

    // look and up need not be unit or orthogonal; up is re-orthogonalized against look (Gram-Schmidt).
    // Throws InputError if look is zero or parallel to up.
    static CameraCluster from_look_up(glm::vec3 look, glm::vec3 up);

    FaceBasis face(Face f) const;              // world-space basis of a face
    glm::vec3 to_cluster(glm::vec3 world) const { return {glm::dot(world, alpha), glm::dot(world, beta), glm::dot(world, gamma)}; }
    glm::vec3 to_world(glm::vec3 c) const { return c.x * alpha + c.y * beta + c.z * gamma; }
};

// Face bases in cluster space (x = alpha/right, y = beta/up, z = gamma/backward):
//   front: look -z, right +x, up +y      back:  look +z, right -x, up +y
//   left:  look -x, right -z, up +y      right: look +x, right +z, up +y
//   up:    look +y, right +x, up +z      down:  look -y, right +x, up -z
FaceBasis cluster_face_basis(Face f);

// Direction (not normalized) through the centre of pixel (col, row) of an N x N face: row 0 is the top of the
// image, col 0 the left. u = 2(col+0.5)/N - 1, v = 1 - 2(row+0.5)/N, d = look + u*right + v*up (90 deg FOV).
glm::vec3 face_pixel_direction(const FaceBasis& b, int col, int row, int n);

// The inverse: which face a direction hits and where, as continuous pixel coordinates (col, row) in [0, N)
// (pixel centres at +0.5). Ties on face edges go to the first face in enum order.
struct FaceSample {
    Face face;
    float col, row;
};
FaceSample direction_to_face(glm::vec3 cluster_dir, int n);

}  // namespace ngi
