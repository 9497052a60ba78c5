// Seed 001's AO network (ngi::AoNetwork, pipeline/ao.cpp): the "ao" object of an "mlp" model file's metadata
// (docs/MODEL_FORMAT.md "mlp"), read here so that the model file has one reader. Library-internal; the pipeline gets
// it through ModelAccess::ao (models/model_access.hpp).
#pragma once
#include <string>

#include <nlohmann/json.hpp>

namespace ngi::detail {

// Ring points of the AO network's input ("ao.neighbours"; ngi::AoNetwork::kRingPoints).
inline constexpr int kAoNeighbours = 16;

struct AoMetadata {
    float radius_px = 0;             // the ring radius of the training data, in its pixels (0..1024)
    int at_size = 0;                 // the training images' height in pixels (1..65536)
    std::string normals = "smooth";  // the normals it was trained on: "smooth" | "face"
};

// `ao`: the metadata's "ao" value (null when it has none). Every field checked for its JSON type and range; an
// InputError starting with `what` names the first that is missing or out of range (other fields are informative
// and ignored).
AoMetadata parse_ao_metadata(const nlohmann::json& ao, const std::string& what);

}  // namespace ngi::detail
