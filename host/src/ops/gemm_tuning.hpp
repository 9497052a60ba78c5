// The GEMM tuning database (CLBlast style): per-device knob sets measured by `ngi_bench tune` and compiled into the
// library (kernels/gemm_tuning.json, embedded at build time). Lookup goes from the most specific entry that matches
// the device (platform + vendor + device name + driver) to the least (device type with its native float vector
// width, the type alone, then the default), so a device nobody tuned still gets its type's starting point. Every
// choice is then confirmed by the self-check (ops/gemm_selfcheck.hpp) before a model uses it.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "ngi/device.hpp"
#include "ops/gemm.hpp"

namespace ngi::detail {

struct GemmTuningEntry {
    // Fields that must equal the device's (empty = any): DeviceInfo::platform_name, vendor, name, driver_version,
    // the type ("cpu", "gpu", "other") and native_float_vector_width as text ("8": AVX2, "16": AVX-512).
    std::string platform, vendor, device, driver, type, vector_width;
    GemmParams params;
    // The implicit-GEMM convolution's knob set (gemm_conv, ops/conv_implicit.hpp) where it was tuned apart: its B
    // operand comes from a padded image, not a packed panel, and prefers other tiles. Unset: `params`.
    std::optional<GemmParams> conv_params;
    bool conv_im2col = false;  // conv_params "im2col": the implicit path is off on matching devices
    std::string note;     // where the numbers came from (tool, date, what was measured)
    int specificity() const;  // device > driver > vendor > platform > type > vector width; 0 = the default
    bool matches(const DeviceInfo& info) const;
};

// Parses the database (JSON: {"entries": [{"match": {...}, "params": "MR,VW,...", "note": "..."}]}); `name` names it
// in errors. Every entry's params are validated (parse_gemm_params); an unknown match key is an error.
std::vector<GemmTuningEntry> parse_gemm_tuning(const std::string& json_text, const std::string& name);

// The database compiled into this library.
const std::vector<GemmTuningEntry>& gemm_tuning_database();

// The most specific entry matching `info` (ties: the first in the file), or nullptr.
const GemmTuningEntry* find_gemm_tuning(const std::vector<GemmTuningEntry>& db, const DeviceInfo& info);

// The implicit convolution's knob set: $NGI_CONV_GEMM if set, else the matching entry's conv_params, else `gemm`
// (the device's checked GEMM set); nullopt where the entry says "im2col" (the implicit path measured slower there).
// gemm_conv has no local-memory variant: KWG must be 0.
std::optional<GemmParams> conv_params_for(const DeviceInfo& info, const GemmParams& gemm);

// The database as JSON text with `entry` added, replacing an entry with the same match fields (what
// `ngi_bench tune --write-db` writes back to kernels/gemm_tuning.json).
std::string gemm_tuning_with(const std::string& json_text, const GemmTuningEntry& entry);

}  // namespace ngi::detail
