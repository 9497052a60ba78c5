// Cold start (issue 48): a new process's first frame builds every OpenCL program its path needs -- seconds on PoCL,
// longer on some GPU drivers. ngi keeps built program binaries in its program cache (program_cache_dir()), and PoCL
// keeps its per-work-group-size kernel code in $POCL_CACHE_DIR; later processes load them. warm_up runs a model's
// whole frame once, at the face size and display size the application will use, so that every program and every
// local size a real frame needs is built and cached before the first real frame: at install time, in a loading
// screen, or once on a build machine whose cache folder the application ships (same device, driver and ngi).
#pragma once
#include <filesystem>
#include <string>

#include "ngi/device.hpp"
#include "ngi/model.hpp"

namespace ngi {

// ngi's program cache folder: $NGI_CACHE_DIR, else $XDG_CACHE_HOME/ngi, else $HOME/.cache/ngi, else <tmp>/ngi-cache.
std::filesystem::path program_cache_dir();

struct WarmUpReport {
    std::string cache_dir;        // program_cache_dir() when the call ran
    int programs_built = 0;       // compiled from source by this call and written to the cache
    int programs_from_cache = 0;  // loaded from the cache by this call
    double first_frame_ms = 0;    // the warm-up frame (program builds or loads included)
    double second_frame_ms = 0;   // the same frame again: what a frame costs once warm
};

// Runs `model` (a frame rung: an image generator the surround pipeline can feed -- ModelConfig::input image, 12 or
// the single view's input channels -- or an ssgi rung, has_network false) on a synthetic frame at face size n through
// SurroundPipeline::enqueue with every output, and, when display_size > 0, through a DisplayView of that size; twice,
// timed. Throws InputError for a model that is no frame rung, a face size the pipeline refuses, or a program cache
// folder that cannot be created or written (checked first, before any work: nothing is left behind).
WarmUpReport warm_up(const Device& device, Model& model, int n, int display_size = 0);

}  // namespace ngi
