// What reading a frame folder replaced, said by every command that scores a frame (issue 31, "a score that lies"):
// a frame whose files held NaN or Inf runs (the preprocessing rules replace those values, docs/CONVENTIONS.md
// section 6), but the command warns with the count per file, and its scores are marked invalid: they would compare
// replacement values (an all-NaN front_albedo once scored MSE 0 / SSIM 1 against its reference).
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "ngi/image_io.hpp"

namespace ngi_cli {

// "front_albedo.exr: 4096 NaN; left_depth.exr: 3 Inf" (empty when nothing was replaced).
std::string sanitized_files_text(const ngi::FrameReadStats& stats);

// One line on stderr when anything was replaced: "ngi <command>: warning: <dir>: N NaN/Inf values replaced on
// read (...); its scores are not valid".
void warn_frame_sanitized(const char* command, const std::string& frame_dir, const ngi::FrameReadStats& stats);
// A frame rendered by `ngi render` records its direct-light samples per pixel in render.json: below a quarter of an
// engine's converged input (ngi::kEngineFeatureSpp) the direct light is noisy, which no engine's is, and a rung
// scored on it is scored on the tracer's noise (issue 45). Warns naming the level; silent without a render.json
// or with one that does not say (frames of `ngi dataset`, an application's own).
void warn_noisy_direct_light(const char* command, const std::string& frame_dir);

// When anything was replaced: every score object of `metrics` (an object with "mse", "psnr" and "ssim") gets null
// scores and a note, and metrics gains "scores_valid": false and "frame_sanitized": [{"file", "nan", "inf"}, ...].
// Otherwise metrics gains "scores_valid": true.
void mark_scores(nlohmann::json& metrics, const ngi::FrameReadStats& stats);

}  // namespace ngi_cli
