// The lightmap at display resolution, accumulated over frames (ngi::DisplayView): one handle per view, fed the
// pipeline's planes and lightmap and the display's own S x S planes, on the device.
#include "c_handles.hpp"

using namespace c_abi;

extern "C" {

ngi_status ngi_display_new(ngi_device* device, int size, ngi_display_upsampler upsampler, int temporal,
                           ngi_display** out) {
    return guarded(__func__, [&] {
        require(out, "out is NULL");
        *out = nullptr;
        const ngi_device& d = live(device, "device");
        require(upsampler == NGI_DISPLAY_JBU || upsampler == NGI_DISPLAY_BILINEAR,
                "upsampler " + std::to_string(int(upsampler)) + " is not an ngi_display_upsampler");
        ngi::DisplaySettings s;
        s.upsampler = upsampler == NGI_DISPLAY_JBU ? ngi::DisplayUpsampler::Jbu : ngi::DisplayUpsampler::Bilinear;
        s.temporal = temporal != 0;
        *out = track(std::make_unique<ngi_display>(d.device, size, s));
    });
}

ngi_status ngi_display_reset(ngi_display* display) {
    return guarded(__func__, [&] { live(display, "display").view.reset(); });
}

ngi_status ngi_display_enqueue(ngi_display* display, int n, ngi_buffer* low_planes, ngi_buffer* low_lightmap,
                               ngi_buffer* display_planes, unsigned flags, const float position[3], const float look[3],
                               const float up[3], ngi_buffer* lightmap, ngi_buffer* final_image,
                               ngi_buffer* display_image) {
    return guarded(__func__, [&] {
        ngi_display& v = live(display, "display");
        require(position && look && up, "position, look and up must not be NULL");
        require((flags & ~unsigned(NGI_FRAME_EMISSION | NGI_FRAME_ENV)) == 0,
                "flags " + std::to_string(flags) + " are not ngi_frame_flags");
        require(lightmap || final_image || display_image, "lightmap, final_image and display_image are all NULL: "
                                                          "nothing to make");
        ngi::FrameDesc desc;
        desc.faces = 1;
        desc.has_emission = (flags & NGI_FRAME_EMISSION) != 0;
        desc.has_env = (flags & NGI_FRAME_ENV) != 0;
        desc.look = glm::vec3(look[0], look[1], look[2]);
        desc.up = glm::vec3(up[0], up[1], up[2]);
        ngi::FrameOutputs outs;
        if (lightmap) outs.lightmap = live(lightmap, "lightmap").buffer;
        if (final_image) outs.final_image = live(final_image, "final_image").buffer;
        if (display_image) outs.display = live(display_image, "display_image").buffer;
        v.view.enqueue(n, live(low_planes, "low_planes").buffer, live(low_lightmap, "low_lightmap").buffer,
                       live(display_planes, "display_planes").buffer, desc,
                       glm::vec3(position[0], position[1], position[2]), outs);
    });
}

ngi_status ngi_display_retain(ngi_display* display) { return guarded(__func__, [&] { retain_handle(display, "display"); }); }
ngi_status ngi_display_release(ngi_display* display) { return guarded(__func__, [&] { release_handle(display, "display"); }); }

}  // extern "C"
