// Family "ssgi" (docs/MODEL_FORMAT.md "ssgi"): a rung with no network and no tensors. Its file holds the gather's
// settings (read here; the family's front-end is models/ssgi_family.cpp); the surround pipeline computes the light
// (host/src/pipeline/ssgi.cpp). Library-internal.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "ngi/model.hpp"

namespace ngi::detail {

// Largest cluster_level (blocks of 2^level x 2^level texels) and bounce count accepted.
constexpr int kSsgiMaxClusterLevel = 5;
constexpr int kSsgiMaxBounces = 4;
// Largest visibility_steps accepted: samples per pair multiply the gather's cost.
constexpr int kSsgiMaxVisibilitySteps = 64;
// Input channels of a network that corrects SSGI: the front view's 10 and the SSGI estimate's 3, named by
// ngi::ssgi_residual_input_channels() (the pipeline checks that list against this count).
constexpr int kSsgiResidualInputs = 13;

// Reads the gather's settings present in `j` into `s` (absent ones keep their defaults), each range-checked; `what`
// starts every error. Family ssgi's front-end (models/ssgi_family.cpp) reads its config's top level with it.
void read_ssgi_gather_fields(const nlohmann::json& j, const std::string& what, ModelConfig::Ssgi& s);
// "view, cluster_level, bounces, near_factor, min_distance, visibility_steps, thickness": what messages list.
const char* ssgi_gather_field_names();

// The gather's settings of a network that corrects SSGI (pix2pix_unet, output_mode "ssgi_residual"): its metadata
// field "ssgi", an object of the fields above (view, cluster_level, bounces, near_factor, min_distance,
// visibility_steps, thickness; absent ones take ModelConfig::Ssgi's defaults, unknown ones are refused). `what` starts
// every error message.
ModelConfig::Ssgi parse_ssgi_gather(const nlohmann::json& j, const std::string& what);

}  // namespace ngi::detail
