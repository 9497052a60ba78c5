// The G-buffer pass: the six 90-degree faces of the camera cluster rasterized into one framebuffer object of
// N x 6N texels (face f in rows [f N, f N + N), GL's bottom-up rows), in the formats a GL engine renders its
// G-buffer in, handed to ngi as they are (issue 48: the image descriptors' engine formats and encodings):
//
//   attachment  format       holds
//   0 albedo    RGBA16F      block albedo (linear), 0 on sky
//   1 normal    RG16F        world-space unit face normal, octahedral map (ngi::NormalEncoding::Octahedral); the
//                            sky's (0, 0) is "no normal" by the depth (ngi takes the zero vector there)
//   depth       D32F         the depth attachment itself: window depth of the faces' perspective projection
//                            (standard Z, kNear, kFar; ngi::DepthEncoding::Perspective), the cleared 1 on sky
//   3 direct    R11G11B10F   irradiance / pi: sun x max(0, n.l) / pi x shadow map (PCF) + baked sky and emitters
//                            + lamp_level x baked lamps, 0 on sky
//   4 emission  RGBA16F      emitted radiance (lamps x lamp_level), 0 on sky
//   5 env       RGBA16F      0 on surfaces; on sky the sky radiance toward the pixel (sun disc excluded), from a
//                            full-screen pass evaluating ngi::sky_radiance's formula
//
// Read back with glReadPixels into one pixel buffer object per attachment (the depth attachment included) and
// mapped: those mappings are what the viewer hands to ngi as host images (ngi::ImageDesc, bottom_up = true),
// attachment by attachment, no repacking and no decoding on the host.
#pragma once
#include <cstdint>
#include <array>

#include <ngi/image.hpp>
#include <ngi/image_desc.hpp>
#include <ngi/render.hpp>

#include "gl_context.hpp"
#include "gpu_mesh.hpp"
#include "shadow_map.hpp"

namespace ngi_gl {

class GBufferPass {
public:
    explicit GBufferPass(int n);
    ~GBufferPass();
    GBufferPass(const GBufferPass&) = delete;
    GBufferPass& operator=(const GBufferPass&) = delete;
    int n() const { return n_; }
    // Shadow lookup: PCF radius r ((2r + 1)^2 hardware-bilinear taps) and the offset along the normal in shadow
    // texels. Defaults measured against the tracer (samples/gl/README.md "Agreement with the tracer").
    void set_shadow_filter(int pcf_radius, float normal_offset_texels) {
        pcf_radius_ = pcf_radius;
        normal_offset_texels_ = normal_offset_texels;
    }

    // Rasterizes the six faces of the cluster at `pose` (look/up of the front camera).
    void render(const GpuScene& scene, const ShadowMap& shadow, const ngi::CameraPose& pose,
                const ngi::Lighting& lighting);
    // glReadPixels of every attachment into its PBO, then maps them (blocks until GL has finished).
    void read_back();
    // The mapped attachments as ngi image descriptors ([face][feature]); valid until unmap().
    ngi::FrameInputs inputs(const ngi::CameraPose& pose) const;
    void unmap();
    // The mapped attachments repacked into an ngi::Frame (planar, top row first): for EXR output, the agreement test
    // and the display view (--display: the front face only, faces = 1); the per-frame path hands the mappings over
    // as they are.
    ngi::Frame to_frame(const ngi::CameraPose& pose, int faces = ngi::kFaceCount) const;

    // Bytes of GL storage one pass of face size n allocates: the render targets, the depth buffer and the read-back
    // PBOs (host memory on a software renderer such as llvmpipe: 432 n^2, 1.7 GiB at n = 2048).
    static std::uint64_t gl_bytes(int n);

    static constexpr int kTargets = 6;  // ngi::Feature order; Feature::Depth is the depth attachment
    // The faces' perspective projection (metres): what the depth attachment's window depth decodes with.
    static constexpr float kNear = 0.01f, kFar = 1.0e4f;
private:
    int n_;
    int pcf_radius_ = 1;
    float normal_offset_texels_ = 0.5f;
    GLuint fbo_ = 0, depth_rb_ = 0, gbuffer_program_ = 0, sky_program_ = 0, empty_vao_ = 0;
    std::array<GLuint, kTargets> tex_{}, pbo_{};
    std::array<const void*, kTargets> mapped_{};
    std::size_t bytes(int target) const;
};

}  // namespace ngi_gl
