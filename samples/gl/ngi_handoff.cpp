#include "ngi_handoff.hpp"

namespace ngi_gl {

LitFrame light_frame(ngi::SurroundPipeline& pipeline, ngi::Model& model, const GBufferPass& gbuffer,
                     const ngi::CameraPose& pose, bool lightmap, bool display, const ngi::ToneMapOptions& tonemap) {
    LitFrame out;
    ngi::FrameImages images =
        pipeline.run(model, gbuffer.inputs(pose), lightmap, false, display, tonemap, nullptr, &out.timings);
    out.lightmap = std::move(images.lightmap);
    out.display = std::move(images.display);
    return out;
}

TransferPath choose_transfer_path(const ngi::Device& device) {
    TransferPath t;
    t.gl_sharing_offered = device.info().extensions.find("cl_khr_gl_sharing") != std::string::npos;
    t.note = t.gl_sharing_offered
                 ? "the device offers cl_khr_gl_sharing, but the viewer's interop path is not implemented yet: "
                   "using glReadPixels into PBOs + host images"
                 : "the device does not offer cl_khr_gl_sharing: glReadPixels into PBOs + host images";
    return t;
}

}  // namespace ngi_gl
