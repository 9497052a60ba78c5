#include "gpu_mesh.hpp"

#include <cstddef>
#include <string>

namespace ngi_gl {

GpuScene::GpuScene(const Mesh& mesh, const LightBake& bake) {
    glGenVertexArrays(1, &vao_);
    glBindVertexArray(vao_);
    glGenBuffers(1, &vbo_);
    glBindBuffer(GL_ARRAY_BUFFER, vbo_);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(mesh.vertices.size() * sizeof(Vertex)), mesh.vertices.data(), GL_STATIC_DRAW);
    glGenBuffers(1, &ebo_);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo_);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(mesh.indices.size() * 4), mesh.indices.data(), GL_STATIC_DRAW);
    struct Attr { GLint size; std::size_t offset; };
    const Attr attrs[] = {{3, offsetof(Vertex, position)}, {3, offsetof(Vertex, normal)}, {3, offsetof(Vertex, albedo)},
                          {3, offsetof(Vertex, emission)}, {1, offsetof(Vertex, lamp)},   {2, offsetof(Vertex, tile)},
                          {2, offsetof(Vertex, uv)}};
    for (GLuint i = 0; i < 7; ++i) {
        glEnableVertexAttribArray(i);
        glVertexAttribPointer(i, attrs[i].size, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                              reinterpret_cast<const void*>(attrs[i].offset));
    }
    glBindVertexArray(0);
    count_ = GLsizei(mesh.indices.size());
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    if (bake.width > max_size || bake.height > max_size)
        throw GlError("light bake atlas " + std::to_string(bake.width) + " x " + std::to_string(bake.height) +
                      " exceeds GL_MAX_TEXTURE_SIZE " + std::to_string(max_size) + " (use --bake-texels 1)");
    for (GLuint* t : {&tex_static_, &tex_lamps_}) {
        glGenTextures(1, t);
        glBindTexture(GL_TEXTURE_2D, *t);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);  // bilinear between texel centres of a face
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    }
    update_bake(bake);
    check_gl("uploading the voxel mesh and light atlas");
}

void GpuScene::update_bake(const LightBake& bake) {
    k_ = bake.k;
    atlas_ = glm::vec2(float(bake.width), float(bake.height));
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glBindTexture(GL_TEXTURE_2D, tex_static_);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB32F, bake.width, bake.height, 0, GL_RGB, GL_FLOAT, bake.sky_static.data());
    glBindTexture(GL_TEXTURE_2D, tex_lamps_);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB32F, bake.width, bake.height, 0, GL_RGB, GL_FLOAT, bake.lamps.data());
    check_gl("uploading the light atlas");
}

void GpuScene::draw() const {
    glBindVertexArray(vao_);
    glDrawElements(GL_TRIANGLES, count_, GL_UNSIGNED_INT, nullptr);
    glBindVertexArray(0);
}

GpuScene::~GpuScene() {
    glDeleteTextures(1, &tex_static_);
    glDeleteTextures(1, &tex_lamps_);
    glDeleteBuffers(1, &vbo_);
    glDeleteBuffers(1, &ebo_);
    glDeleteVertexArrays(1, &vao_);
}

}  // namespace ngi_gl
