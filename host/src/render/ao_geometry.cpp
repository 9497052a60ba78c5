// The Renderer's per-pixel renders for per-pixel networks (seed 001; the tracer program ao_geometry:
// kernels/render_ao.cl, render_geometry.cl): ambient occlusion, object-space geometry, the visible mesh surface.
#include <algorithm>
#include <string>

#include "ngi/error.hpp"
#include "ngi/render.hpp"
#include "render/renderer_impl.hpp"

namespace ngi {

Image Renderer::render_ao(const CameraPose& pose, const RenderSettings& s, int rays, float max_distance, Face face) {
    Impl::check_settings(s);
    if (rays < 1 || rays > (1 << 20))
        throw InputError("render ambient occlusion: rays per pixel " + std::to_string(rays) + " not in 1..1048576");
    if (!(max_distance > 0.0f))
        throw InputError("render ambient occlusion: max distance " + std::to_string(max_distance) + " must be > 0");
    Impl& m = *impl_;
    m.upload_frame(pose, Lighting{}, s, nullptr);
    const std::size_t npix = std::size_t(s.n) * s.n;
    const std::size_t local = Impl::local_size(m.kernel(m.k_ao, "ao_geometry", "pt_ao"));
    if (m.ao.bytes() < npix * sizeof(float)) m.ao = m.ctx->alloc(npix * sizeof(float), "render: ambient occlusion");
    const int chunk = m.samples_per_launch(0, "render: ambient occlusion");
    const float dist = std::min(max_distance, 1.0e30f);  // the tracer's "no limit"
    for (int first = 0; first < rays; first += chunk) {
        const int last = std::min(rays, first + chunk);
        m.set_scene_args(m.k_ao, s, m.cam, int(face), s.n, rays, first, last, dist, std::uint32_t(s.seed), m.ao);
        m.ctx->launch(m.k_ao, 1, &npix, &local);
    }
    Image ao(s.n, s.n, 1);
    m.ctx->read(m.ao, 0, npix * sizeof(float), ao.data.data(), "render: read ambient occlusion");
    return ao;
}

Image Renderer::render_geometry(const CameraPose& pose, const RenderSettings& s, float smooth_sigma, Face face) {
    Impl::check_settings(s);
    if (!(smooth_sigma >= 0.0f && smooth_sigma <= kMaxSmoothSigma))
        throw InputError("render geometry: smoothing sigma " + std::to_string(smooth_sigma) + " not in 0.." +
                         std::to_string(kMaxSmoothSigma) + " blocks");
    Impl& m = *impl_;
    m.upload_frame(pose, Lighting{}, s, nullptr);
    const std::size_t npix = std::size_t(s.n) * s.n;
    if (m.geometry.bytes() < 7 * npix * sizeof(float))
        m.geometry = m.ctx->alloc(7 * npix * sizeof(float), "render: geometry");
    m.set_scene_args(m.kernel(m.k_geometry, "ao_geometry", "pt_geometry"), s, m.cam, int(face), s.n, smooth_sigma,
                     m.geometry);
    const std::size_t local = Impl::local_size(m.k_geometry);
    m.ctx->launch(m.k_geometry, 1, &npix, &local);
    Image g(s.n, s.n, 7);
    m.ctx->read(m.geometry, 0, 7 * npix * sizeof(float), g.data.data(), "render: read geometry");
    return g;
}

Image Renderer::render_surface(const CameraPose& pose, const RenderSettings& s, Face face) {
    Impl::check_settings(s);
    Impl& m = *impl_;
    m.upload_frame(pose, Lighting{}, s, nullptr);
    const std::size_t npix = std::size_t(s.n) * s.n;
    if (m.geometry.bytes() < 7 * npix * sizeof(float))
        m.geometry = m.ctx->alloc(7 * npix * sizeof(float), "render: geometry");
    m.set_scene_args(m.kernel(m.k_surface, "ao_geometry", "pt_surface"), s, m.cam, int(face), s.n, m.geometry);
    const std::size_t local = Impl::local_size(m.k_surface);
    m.ctx->launch(m.k_surface, 1, &npix, &local);
    Image g(s.n, s.n, 6);
    m.ctx->read(m.geometry, 0, 6 * npix * sizeof(float), g.data.data(), "render: read surface");
    return g;
}

}  // namespace ngi
