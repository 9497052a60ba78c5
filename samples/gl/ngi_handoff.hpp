// The one place the viewer hands its render targets to ngi: the mapped G-buffer attachments as image descriptors
// (host images, OpenGL's bottom-up rows, the attachments' own formats and strides), one SurroundPipeline::run.
#pragma once
#include <string>

#include <ngi/device.hpp>
#include <ngi/model.hpp>
#include <ngi/pipeline.hpp>

#include "gbuffer_pass.hpp"

namespace ngi_gl {

struct LitFrame {
    ngi::Image lightmap, display;  // N x N x 3 planar; empty when not asked for
    ngi::FrameTimings timings;     // gather (upload + descriptor gather), input, network, outputs
};

LitFrame light_frame(ngi::SurroundPipeline& pipeline, ngi::Model& model, const GBufferPass& gbuffer,
                     const ngi::CameraPose& pose, bool lightmap, bool display, const ngi::ToneMapOptions& tonemap = {});

// How the G-buffer reaches the OpenCL device: "pbo-host" (glReadPixels into pixel buffer objects, handed over as
// host images; ngi uploads them in one transfer). cl_khr_gl_sharing would let ngi read the GL textures in place;
// the viewer reports whether the device offers it, but that path is not implemented yet.
struct TransferPath {
    bool gl_sharing_offered = false;
    std::string used = "pbo-host";
    std::string note;
};
TransferPath choose_transfer_path(const ngi::Device& device);

}  // namespace ngi_gl
