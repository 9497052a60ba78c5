// The voxel mesh and the baked light atlas on the GPU (one VAO, two RGB float textures).
#pragma once
#include "gl_context.hpp"
#include "light_bake.hpp"
#include "voxel_mesh.hpp"

namespace ngi_gl {

class GpuScene {
public:
    GpuScene(const Mesh& mesh, const LightBake& bake);
    ~GpuScene();
    GpuScene(const GpuScene&) = delete;
    GpuScene& operator=(const GpuScene&) = delete;
    void update_bake(const LightBake& bake);  // a new time of day: same atlas layout, new values
    void draw() const;                        // the whole mesh with the bound program
    GLuint bake_static() const { return tex_static_; }
    GLuint bake_lamps() const { return tex_lamps_; }
    int bake_k() const { return k_; }
    glm::vec2 atlas_size() const { return atlas_; }
private:
    GLuint vao_ = 0, vbo_ = 0, ebo_ = 0, tex_static_ = 0, tex_lamps_ = 0;
    GLsizei count_ = 0;
    int k_ = 1;
    glm::vec2 atlas_{1.0f};
};

}  // namespace ngi_gl
