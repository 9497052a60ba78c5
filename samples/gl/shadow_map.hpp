// The sun's shadow map: an orthographic depth map of the whole grid seen from the sun, rendered with front faces
// culled (the mesh is closed, so the stored depth is the far side of the first solid: no acne on lit faces), read
// with 3 x 3 hardware-PCF taps (each a bilinear 2 x 2 compare) in gbuffer_pass. Static scene and sun: rendered
// once per time of day, as engines cache static shadows.
#pragma once
#include <glm/glm.hpp>

#include "gl_context.hpp"
#include "gpu_mesh.hpp"

namespace ngi_gl {

class ShadowMap {
public:
    explicit ShadowMap(int resolution);
    ~ShadowMap();
    ShadowMap(const ShadowMap&) = delete;
    ShadowMap& operator=(const ShadowMap&) = delete;
    // Renders the scene's depth from the sun (unit direction toward it) over the grid box [0, size).
    void render(const GpuScene& scene, glm::vec3 sun_dir, glm::ivec3 grid_size);
    GLuint texture() const { return tex_; }
    const glm::mat4& light_view_projection() const { return vp_; }
    int resolution() const { return res_; }
    float texel_metres() const { return texel_m_; }  // world size of one texel
    float depth_range() const { return range_; }     // metres spanned by depth 0..1
private:
    int res_;
    GLuint tex_ = 0, fbo_ = 0, program_ = 0;
    glm::mat4 vp_{1.0f};
    float texel_m_ = 0, range_ = 1;
};

}  // namespace ngi_gl
