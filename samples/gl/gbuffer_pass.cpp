#include "gbuffer_pass.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <ngi/camera.hpp>

namespace ngi_gl {
namespace {

const char* kGbufferVs = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec3 a_albedo;
layout(location = 3) in vec3 a_emission;
layout(location = 4) in float a_lamp;
layout(location = 5) in vec2 a_tile;
layout(location = 6) in vec2 a_uv;
uniform mat4 u_vp;
out vec3 v_world;
out vec2 v_uv;
flat out vec3 v_normal, v_albedo, v_emission;
flat out float v_lamp;
flat out vec2 v_tile;
void main() {
    v_world = a_position; v_uv = a_uv;
    v_normal = a_normal; v_albedo = a_albedo; v_emission = a_emission; v_lamp = a_lamp; v_tile = a_tile;
    gl_Position = u_vp * vec4(a_position, 1.0);
}
)";

const char* kGbufferFs = R"(#version 330 core
in vec3 v_world;
in vec2 v_uv;
flat in vec3 v_normal, v_albedo, v_emission;
flat in float v_lamp;
flat in vec2 v_tile;
uniform vec3 u_centre, u_look;
uniform vec3 u_sun_dir, u_sun_e;
uniform float u_lamp_level;
uniform mat4 u_light_vp;
uniform sampler2DShadow u_shadow;
uniform float u_shadow_texel;      // 1 / resolution
uniform float u_normal_offset;     // metres along the normal before the lookup
uniform int u_pcf;                 // PCF taps: (2 u_pcf + 1)^2, each a bilinear 2 x 2 compare
uniform float u_shadow_bias;       // depth units
uniform sampler2D u_bake_static, u_bake_lamp;
uniform float u_bake_k;
uniform vec2 u_atlas_size;
layout(location = 0) out vec4 o_albedo;
layout(location = 1) out vec2 o_normal;   // octahedral
layout(location = 3) out vec3 o_direct;   // R11G11B10F
layout(location = 4) out vec4 o_emission;
layout(location = 5) out vec4 o_env;
const float kInvPi = 0.318309886;
// The octahedral map of a unit vector (Cigolle et al. 2014): what ngi::NormalEncoding::Octahedral decodes.
vec2 octahedral(vec3 n) {
    vec2 p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    return n.z >= 0.0 ? p : (1.0 - abs(p.yx)) * vec2(p.x >= 0.0 ? 1.0 : -1.0, p.y >= 0.0 ? 1.0 : -1.0);
}
void main() {
    vec3 n = v_normal;
    vec3 sun = vec3(0.0);
    float ndl = dot(n, u_sun_dir);
    if (ndl > 0.0 && u_sun_e.r + u_sun_e.g + u_sun_e.b > 0.0) {
        vec3 c = (u_light_vp * vec4(v_world + n * u_normal_offset, 1.0)).xyz * 0.5 + 0.5;
        float vis = 0.0;
        for (int j = -u_pcf; j <= u_pcf; ++j)
            for (int i = -u_pcf; i <= u_pcf; ++i)
                vis += texture(u_shadow, vec3(c.xy + vec2(i, j) * u_shadow_texel, c.z - u_shadow_bias));
        float taps = float(2 * u_pcf + 1);
        sun = u_sun_e * (ndl * kInvPi * vis / (taps * taps));
    }
    // Baked static light: bilinear between the face's texel centres, clamped inside its own tile.
    vec2 t = clamp(v_uv * u_bake_k, vec2(0.5), vec2(u_bake_k - 0.5)) + v_tile;
    vec2 tc = t / u_atlas_size;
    vec3 baked = texture(u_bake_static, tc).rgb + u_lamp_level * texture(u_bake_lamp, tc).rgb;
    o_albedo = vec4(v_albedo, 1.0);
    o_normal = octahedral(n);
    o_direct = sun + baked;
    o_emission = vec4(v_emission * (v_lamp > 0.5 ? u_lamp_level : 1.0), 1.0);
    o_env = vec4(0.0);
}
)";

// Background: a full-screen triangle at the far plane, drawn where no surface was (depth test LEQUAL against the
// cleared 1.0, depth not written: the cleared 1 is ngi's "no surface"), writing what the tracer writes where a
// primary ray escapes.
const char* kSkyVs = R"(#version 330 core
void main() {
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2) * 2.0 - 1.0;
    gl_Position = vec4(p, 1.0, 1.0);
}
)";

const char* kSkyFs = R"(#version 330 core
uniform vec3 u_look, u_right, u_up;
uniform float u_n, u_row0;
uniform vec3 u_zenith, u_horizon, u_ground, u_glow, u_sun_dir;
layout(location = 0) out vec4 o_albedo;
layout(location = 1) out vec2 o_normal;
layout(location = 3) out vec3 o_direct;
layout(location = 4) out vec4 o_emission;
layout(location = 5) out vec4 o_env;
vec3 sky_radiance(vec3 d) {   // ngi::sky_radiance / pathtrace.cl sky_radiance
    if (d.y < 0.0) return u_ground;
    float g = 0.5 * (1.0 + dot(d, u_sun_dir));
    g *= g; g *= g; g *= g;
    return u_horizon + (u_zenith - u_horizon) * sqrt(d.y) + u_glow * g;
}
void main() {
    // gl_FragCoord is the pixel centre; GL rows count from the bottom, so v = 2 (y + 0.5) / N - 1 is camera.hpp's
    // v = 1 - 2 (row + 0.5) / N with row = N - 1 - y.
    float u = 2.0 * gl_FragCoord.x / u_n - 1.0;
    float v = 2.0 * (gl_FragCoord.y - u_row0) / u_n - 1.0;
    vec3 d = normalize(u_look + u * u_right + v * u_up);
    o_albedo = vec4(0.0); o_normal = vec2(0.0); o_direct = vec3(0.0); o_emission = vec4(0.0);
    o_env = vec4(sky_radiance(d), 1.0);
}
)";

struct TargetFormat {
    GLenum internal, format, type;
    ngi::PixelFormat ngi_format;
    int channels;
    std::size_t pixel_bytes;
};
constexpr int kDepth = int(ngi::Feature::Depth);  // read from the depth attachment, no colour target
const TargetFormat kFormats[GBufferPass::kTargets] = {
    {GL_RGBA16F, GL_RGBA, GL_HALF_FLOAT, ngi::PixelFormat::F16, 4, 8},                              // albedo
    {GL_RG16F, GL_RG, GL_HALF_FLOAT, ngi::PixelFormat::F16, 2, 4},                                  // normal
    {GL_DEPTH_COMPONENT32F, GL_DEPTH_COMPONENT, GL_FLOAT, ngi::PixelFormat::F32, 1, 4},             // depth
    {GL_R11F_G11F_B10F, GL_RGB, GL_UNSIGNED_INT_10F_11F_11F_REV, ngi::PixelFormat::R11G11B10F, 3, 4},  // direct
    {GL_RGBA16F, GL_RGBA, GL_HALF_FLOAT, ngi::PixelFormat::F16, 4, 8},                              // emission
    {GL_RGBA16F, GL_RGBA, GL_HALF_FLOAT, ngi::PixelFormat::F16, 4, 8},                              // env
};

GLint loc(GLuint p, const char* name) { return glGetUniformLocation(p, name); }
void set3(GLuint p, const char* name, glm::vec3 v) { glUniform3fv(loc(p, name), 1, glm::value_ptr(v)); }

float half_to_float(std::uint16_t h) {
    const std::uint32_t sign = std::uint32_t(h >> 15) << 31, exp = (h >> 10) & 31, man = h & 1023;
    std::uint32_t bits;
    if (exp == 0) {
        if (man == 0) bits = sign;
        else {  // subnormal
            float f = std::ldexp(float(man), -24);
            return sign ? -f : f;
        }
    } else if (exp == 31) bits = sign | 0x7F800000u | (man << 13);
    else bits = sign | ((exp + 112) << 23) | (man << 13);
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
}

// An unsigned small float of a packed R11G11B10F word: 5 exponent bits (bias 15) above `man` mantissa bits.
float ufloat(std::uint32_t bits, int man) {
    const std::uint32_t e = bits >> man, m = bits & ((1u << man) - 1u);
    if (e == 31) return m ? std::numeric_limits<float>::quiet_NaN() : std::numeric_limits<float>::infinity();
    return e == 0 ? std::ldexp(float(m), -14 - man) : std::ldexp(float((1u << man) + m), int(e) - 15 - man);
}

// The unit vector of an octahedral map value (Cigolle et al. 2014).
glm::vec3 from_octahedral(float x, float y) {
    glm::vec3 v(x, y, 1.0f - std::abs(x) - std::abs(y));
    if (v.z < 0.0f) v = {(1.0f - std::abs(y)) * (x >= 0.0f ? 1.0f : -1.0f), (1.0f - std::abs(x)) * (y >= 0.0f ? 1.0f : -1.0f), v.z};
    return glm::normalize(v);
}

}  // namespace

GBufferPass::GBufferPass(int n) : n_(n) {
    glGenFramebuffers(1, &fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    GLenum draw[kTargets];
    for (int i = 0; i < kTargets; ++i) {
        if (i == kDepth) {  // the depth attachment below: no colour output at this location
            draw[i] = GL_NONE;
            continue;
        }
        glGenTextures(1, &tex_[i]);
        glBindTexture(GL_TEXTURE_2D, tex_[i]);
        glTexImage2D(GL_TEXTURE_2D, 0, kFormats[i].internal, n_, 6 * n_, 0, kFormats[i].format, kFormats[i].type, nullptr);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + i, GL_TEXTURE_2D, tex_[i], 0);
        draw[i] = GL_COLOR_ATTACHMENT0 + i;
    }
    glDrawBuffers(kTargets, draw);
    glGenRenderbuffers(1, &depth_rb_);
    glBindRenderbuffer(GL_RENDERBUFFER, depth_rb_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, n_, 6 * n_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_rb_);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw GlError("G-buffer framebuffer (" + std::to_string(n_) + " x " + std::to_string(6 * n_) +
                      ", 6 render targets) is incomplete");
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    for (int i = 0; i < kTargets; ++i) {
        glGenBuffers(1, &pbo_[i]);
        glBindBuffer(GL_PIXEL_PACK_BUFFER, pbo_[i]);
        glBufferData(GL_PIXEL_PACK_BUFFER, GLsizeiptr(bytes(i)), nullptr, GL_STREAM_READ);
    }
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    gbuffer_program_ = make_program("G-buffer", kGbufferVs, kGbufferFs);
    sky_program_ = make_program("sky background", kSkyVs, kSkyFs);
    glGenVertexArrays(1, &empty_vao_);
    check_gl("creating the G-buffer pass");
}

GBufferPass::~GBufferPass() {
    unmap();
    glDeleteVertexArrays(1, &empty_vao_);
    glDeleteProgram(gbuffer_program_);
    glDeleteProgram(sky_program_);
    for (int i = 0; i < kTargets; ++i) {
        glDeleteBuffers(1, &pbo_[i]);
        glDeleteTextures(1, &tex_[i]);
    }
    glDeleteRenderbuffers(1, &depth_rb_);
    glDeleteFramebuffers(1, &fbo_);
}

std::uint64_t GBufferPass::gl_bytes(int n) {
    std::uint64_t per_pixel = 0;
    for (int i = 0; i < kTargets; ++i)  // texture (the depth renderbuffer for depth) + read-back PBO
        per_pixel += 2 * std::uint64_t(kFormats[i].pixel_bytes);
    return per_pixel * 6 * std::uint64_t(n) * std::uint64_t(n);
}

std::size_t GBufferPass::bytes(int target) const {
    return std::size_t(n_) * 6 * n_ * kFormats[target].pixel_bytes;
}

void GBufferPass::render(const GpuScene& scene, const ShadowMap& shadow, const ngi::CameraPose& pose,
                         const ngi::Lighting& lighting) {
    const ngi::CameraCluster cluster = ngi::CameraCluster::from_look_up(pose.look, pose.up);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glViewport(0, 0, n_, 6 * n_);
    glDisable(GL_SCISSOR_TEST);
    glDepthMask(GL_TRUE);
    glClear(GL_DEPTH_BUFFER_BIT);  // every colour texel is written below: by a surface or by the sky pass
    glEnable(GL_DEPTH_TEST);
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);

    glUseProgram(gbuffer_program_);
    const GLuint p = gbuffer_program_;
    set3(p, "u_centre", pose.position);
    set3(p, "u_sun_dir", lighting.sun.direction);
    set3(p, "u_sun_e", lighting.sun.irradiance);
    glUniform1f(loc(p, "u_lamp_level"), lighting.lamp_level);
    glUniformMatrix4fv(loc(p, "u_light_vp"), 1, GL_FALSE, glm::value_ptr(shadow.light_view_projection()));
    glUniform1f(loc(p, "u_shadow_texel"), 1.0f / float(shadow.resolution()));
    glUniform1f(loc(p, "u_normal_offset"), normal_offset_texels_ * shadow.texel_metres());
    glUniform1i(loc(p, "u_pcf"), pcf_radius_);
    glUniform1f(loc(p, "u_shadow_bias"), 0.5f * shadow.texel_metres() / shadow.depth_range());
    glUniform1f(loc(p, "u_bake_k"), float(scene.bake_k()));
    glUniform2f(loc(p, "u_atlas_size"), scene.atlas_size().x, scene.atlas_size().y);
    glUniform1i(loc(p, "u_shadow"), 0);
    glUniform1i(loc(p, "u_bake_static"), 1);
    glUniform1i(loc(p, "u_bake_lamp"), 2);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, shadow.texture());
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, scene.bake_static());
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D, scene.bake_lamps());
    glDepthFunc(GL_LESS);
    for (int f = 0; f < ngi::kFaceCount; ++f) {
        const ngi::FaceBasis b = cluster.face(ngi::Face(f));
        // 90-degree square frustum: x_ndc = p.right / p.look, y_ndc = p.up / p.look, so pixel centres sample
        // exactly camera.hpp's rays d = look + u right + v up.
        const glm::mat4 view = glm::lookAt(pose.position, pose.position + b.look, b.up);
        const glm::mat4 proj = glm::perspective(glm::half_pi<float>(), 1.0f, kNear, kFar);
        const glm::mat4 vp = proj * view;
        glViewport(0, f * n_, n_, n_);
        glUniformMatrix4fv(loc(p, "u_vp"), 1, GL_FALSE, glm::value_ptr(vp));
        set3(p, "u_look", b.look);
        scene.draw();
    }

    glUseProgram(sky_program_);
    const GLuint s = sky_program_;
    set3(s, "u_zenith", lighting.sky.zenith);
    set3(s, "u_horizon", lighting.sky.horizon);
    set3(s, "u_ground", lighting.sky.ground);
    set3(s, "u_glow", lighting.sky.glow);
    set3(s, "u_sun_dir", lighting.sun.direction);
    glUniform1f(loc(s, "u_n"), float(n_));
    glDepthFunc(GL_LEQUAL);
    glDepthMask(GL_FALSE);
    glBindVertexArray(empty_vao_);
    for (int f = 0; f < ngi::kFaceCount; ++f) {
        const ngi::FaceBasis b = cluster.face(ngi::Face(f));
        glViewport(0, f * n_, n_, n_);
        set3(s, "u_look", b.look);
        set3(s, "u_right", b.right);
        set3(s, "u_up", b.up);
        glUniform1f(loc(s, "u_row0"), float(f * n_));
        glDrawArrays(GL_TRIANGLES, 0, 3);
    }
    glBindVertexArray(0);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_LESS);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("rasterizing the six faces");
}

void GBufferPass::read_back() {
    unmap();
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    for (int i = 0; i < kTargets; ++i) {
        if (i != kDepth) glReadBuffer(GL_COLOR_ATTACHMENT0 + i);  // GL_DEPTH_COMPONENT reads the depth attachment
        glBindBuffer(GL_PIXEL_PACK_BUFFER, pbo_[i]);
        glReadPixels(0, 0, n_, 6 * n_, kFormats[i].format, kFormats[i].type, nullptr);
    }
    for (int i = 0; i < kTargets; ++i) {
        glBindBuffer(GL_PIXEL_PACK_BUFFER, pbo_[i]);
        mapped_[i] = glMapBufferRange(GL_PIXEL_PACK_BUFFER, 0, GLsizeiptr(bytes(i)), GL_MAP_READ_BIT);
        if (!mapped_[i]) throw GlError("mapping the read-back pixel buffer of G-buffer target " + std::to_string(i));
    }
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    check_gl("reading back the G-buffer");
}

void GBufferPass::unmap() {
    for (int i = 0; i < kTargets; ++i)
        if (mapped_[i]) {
            glBindBuffer(GL_PIXEL_PACK_BUFFER, pbo_[i]);
            glUnmapBuffer(GL_PIXEL_PACK_BUFFER);
            mapped_[i] = nullptr;
        }
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
}

ngi::FrameInputs GBufferPass::inputs(const ngi::CameraPose& pose) const {
    ngi::FrameInputs in;
    in.look = pose.look;
    in.up = pose.up;
    for (int t = 0; t < kTargets; ++t) {
        const std::size_t row = std::size_t(n_) * kFormats[t].pixel_bytes;
        for (int f = 0; f < ngi::kFaceCount; ++f) {
            ngi::ImageDesc& d = in.at(ngi::Face(f), ngi::Feature(t));
            d.host = mapped_[t];
            d.host_bytes = bytes(t);
            d.format = kFormats[t].ngi_format;
            d.channels = kFormats[t].channels;
            d.width = d.height = n_;
            d.offset = std::size_t(f) * n_ * row;  // face f starts at GL row f N
            d.pixel_stride = kFormats[t].pixel_bytes;
            d.row_stride = row;
            d.bottom_up = true;  // GL's first row is the image's bottom
            if (t == int(ngi::Feature::Normal)) d.normal_encoding = ngi::NormalEncoding::Octahedral;
            if (t == kDepth) {
                d.depth_encoding = ngi::DepthEncoding::Perspective;
                d.near_m = kNear;
                d.far_m = kFar;
            }
        }
    }
    return in;
}

ngi::Frame GBufferPass::to_frame(const ngi::CameraPose& pose, int faces) const {
    ngi::Frame frame;
    frame.n = n_;
    frame.look = pose.look;
    frame.up = pose.up;
    for (int t = 0; t < kTargets; ++t)
        if (!mapped_[t]) throw GlError("G-buffer not read back");
    // Decoded as ngi's gather kernel decodes these formats (kernels/gather_image.cl): half floats, R11G11B10F,
    // octahedral normals (the zero vector where the depth is cleared), perspective window depth.
    const auto* depth = static_cast<const float*>(mapped_[kDepth]);
    for (int f = 0; f < std::clamp(faces, 1, ngi::kFaceCount); ++f)
        for (int t = 0; t < kTargets; ++t) {
            ngi::Image img(n_, n_, ngi::feature_channels(ngi::Feature(t)));
            for (int row = 0; row < n_; ++row) {
                const int gl_row = f * n_ + (n_ - 1 - row);
                for (int col = 0; col < n_; ++col) {
                    const std::size_t px = std::size_t(gl_row) * n_ + col;
                    const float d = depth[px];
                    const bool sky = !(d < 1.0f);  // the cleared far plane
                    if (t == kDepth) {
                        img.at(0, row, col) = sky ? 1.0e4f : kNear / (1.0f - d * (1.0f - kNear / kFar));  // the
                        continue;  // tracer's no-surface depth, docs/CONVENTIONS.md section 3
                    }
                    if (kFormats[t].ngi_format == ngi::PixelFormat::R11G11B10F) {
                        std::uint32_t w;
                        std::memcpy(&w, static_cast<const unsigned char*>(mapped_[t]) + px * 4, 4);
                        img.at(0, row, col) = ufloat(w & 2047u, 6);
                        img.at(1, row, col) = ufloat((w >> 11) & 2047u, 6);
                        img.at(2, row, col) = ufloat(w >> 22, 5);
                        continue;
                    }
                    const auto* h = static_cast<const std::uint16_t*>(mapped_[t]) + px * std::size_t(kFormats[t].channels);
                    if (t == int(ngi::Feature::Normal)) {
                        const glm::vec3 nv = sky ? glm::vec3(0.0f) : from_octahedral(half_to_float(h[0]), half_to_float(h[1]));
                        for (int c = 0; c < 3; ++c) img.at(c, row, col) = nv[c];
                        continue;
                    }
                    for (int c = 0; c < img.channels; ++c) img.at(c, row, col) = half_to_float(h[c]);
                }
            }
            frame.get(ngi::Feature(t), ngi::Face(f)) = std::move(img);
        }
    return frame;
}

}  // namespace ngi_gl
