// A plan: which zoo rung `ngi lightmap --plan` runs for a scene, written by `python3 -m ngi.plan` (docs/RESULTS.md,
// "Model only what a scene requires"; the format in docs/MODEL_FORMAT.md, "Plans").
#pragma once

#include <optional>
#include <string>

#include "ngi/image.hpp"

namespace ngi_cli {

struct PlanRung {
    std::string name;     // the zoo rung's name
    std::string model;    // the model file, resolved against the plan file's folder; "" = direct light only
    std::string bn_mode;  // "" = the file's
    int n = 0;            // the face size the rung runs at
};

struct Plan {
    std::string path;
    PlanRung rung;
    // The per-frame switch: frames whose outside_light_share is below `below` run `rung` instead.
    struct Switch {
        double below = 0.0;
        PlanRung rung;
    };
    std::optional<Switch> fallback;
    // The per-frame guard (optional "guard": {"max_indirect_share": T}, 0 < T <= 1): a frame whose
    // ngi::indirect_share of the chosen rung's lightmap exceeds T falls back to direct light alone. `ngi lightmap
    // --guard` overrides it.
    struct Guard {
        double max_indirect_share = 0.0;
    };
    std::optional<Guard> guard;

    // Throws ngi::InputError naming the file and the key for a missing file, bad JSON, a wrong format or version,
    // missing, mistyped or out-of-range keys, a model file that does not exist.
    static Plan load(const std::string& path);
    // The same from the file's text; `path` names the plan in errors and is the base of relative model paths.
    static Plan parse(const std::string& text, const std::string& path);

    // The rung to run for this frame (the switch applied) and the frame's outside light share (-1 when the plan
    // has no switch and it was not computed). Throws ngi::InputError when the frame's face size is not the
    // rung's.
    const PlanRung& choose(const ngi::Frame& frame, double& share) const;
};

}  // namespace ngi_cli
