// Family "ssgi" (docs/MODEL_FORMAT.md "ssgi"): a rung with no network and no tensors. Its file holds the gather's
// settings; the surround pipeline computes the light (host/src/pipeline/ssgi.cpp). Library-internal.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "ngi/model.hpp"

namespace ngi::detail {

// Largest cluster_level (blocks of 2^level x 2^level texels) and bounce count accepted.
constexpr int kSsgiMaxClusterLevel = 5;
constexpr int kSsgiMaxBounces = 4;

// The config of an ssgi file from its parsed metadata object; every field range-checked. InputError naming the file
// and field otherwise.
ModelConfig parse_ssgi_config(const nlohmann::json& j, const std::string& path);

}  // namespace ngi::detail
