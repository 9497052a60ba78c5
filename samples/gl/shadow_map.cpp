#include "shadow_map.hpp"

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

namespace ngi_gl {
namespace {
const char* kVs = R"(#version 330 core
layout(location = 0) in vec3 a_position;
uniform mat4 u_vp;
void main() { gl_Position = u_vp * vec4(a_position, 1.0); }
)";
const char* kFs = R"(#version 330 core
void main() {}
)";
}  // namespace

ShadowMap::ShadowMap(int resolution) : res_(resolution) {
    glGenTextures(1, &tex_);
    glBindTexture(GL_TEXTURE_2D, tex_);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT32F, res_, res_, 0, GL_DEPTH_COMPONENT, GL_FLOAT, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);  // LINEAR + compare mode = 2 x 2 PCF per tap
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    glGenFramebuffers(1, &fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, tex_, 0);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw GlError("shadow map framebuffer (" + std::to_string(res_) + "^2 DEPTH_COMPONENT32F) is incomplete");
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    program_ = make_program("shadow map", kVs, kFs);
    check_gl("creating the shadow map");
}

ShadowMap::~ShadowMap() {
    glDeleteProgram(program_);
    glDeleteFramebuffers(1, &fbo_);
    glDeleteTextures(1, &tex_);
}

void ShadowMap::render(const GpuScene& scene, glm::vec3 sun_dir, glm::ivec3 grid_size) {
    const glm::vec3 centre = glm::vec3(grid_size) * 0.5f;
    const float radius = 0.5f * glm::length(glm::vec3(grid_size)) + 1.0f;  // the grid's bounding sphere
    const glm::vec3 up = std::abs(sun_dir.y) > 0.99f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    const glm::mat4 view = glm::lookAt(centre + sun_dir * (2.0f * radius), centre, up);
    const glm::mat4 proj = glm::ortho(-radius, radius, -radius, radius, radius, 3.0f * radius);
    vp_ = proj * view;
    texel_m_ = 2.0f * radius / float(res_);
    range_ = 2.0f * radius;
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glViewport(0, 0, res_, res_);
    glClear(GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glEnable(GL_CULL_FACE);
    glCullFace(GL_FRONT);
    glUseProgram(program_);
    glUniformMatrix4fv(glGetUniformLocation(program_, "u_vp"), 1, GL_FALSE, glm::value_ptr(vp_));
    scene.draw();
    glCullFace(GL_BACK);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("rendering the shadow map");
}

}  // namespace ngi_gl
