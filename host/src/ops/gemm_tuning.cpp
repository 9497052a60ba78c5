#include "ops/gemm_tuning.hpp"

#include <cstdlib>
#include <nlohmann/json.hpp>

#include "ngi/error.hpp"
#include "runtime/embedded_kernels.hpp"

namespace ngi::detail {

namespace {

using json = nlohmann::json;

const char* const kMatchKeys[] = {"platform", "vendor", "device", "driver", "type", "vector_width"};

std::string* field(GemmTuningEntry& e, const std::string& key) {
    if (key == "platform") return &e.platform;
    if (key == "vendor") return &e.vendor;
    if (key == "device") return &e.device;
    if (key == "driver") return &e.driver;
    if (key == "type") return &e.type;
    if (key == "vector_width") return &e.vector_width;
    return nullptr;
}

json match_json(const GemmTuningEntry& e) {
    json m = json::object();
    GemmTuningEntry copy = e;
    for (const char* k : kMatchKeys)
        if (const std::string* v = field(copy, k); !v->empty()) m[k] = *v;
    return m;
}

}  // namespace

// A device name outranks any combination of vendor, platform, type and vector width (CLBlast's order: device,
// then vendor, then type); a driver version refines a device name. A vector width refines a type alone ("cpu" +
// 8 over "cpu") but not a platform (rusticl's "cpu" entry keeps its reasons on an AVX2 machine).
int GemmTuningEntry::specificity() const {
    return 32 * int(!device.empty()) + 16 * int(!driver.empty()) + 8 * int(!vendor.empty()) +
           4 * int(!platform.empty()) + 2 * int(!type.empty()) + int(!vector_width.empty());
}

bool GemmTuningEntry::matches(const DeviceInfo& info) const {
    return (platform.empty() || platform == info.platform_name) && (vendor.empty() || vendor == info.vendor) &&
           (device.empty() || device == info.name) && (driver.empty() || driver == info.driver_version) &&
           (type.empty() || type == info.type_name()) &&
           (vector_width.empty() || vector_width == std::to_string(info.native_float_vector_width));
}

std::vector<GemmTuningEntry> parse_gemm_tuning(const std::string& json_text, const std::string& name) {
    json db;
    try {
        db = json::parse(json_text);
    } catch (const json::exception& e) {
        throw InputError("GEMM tuning database " + name + ": not valid JSON: " + e.what());
    }
    if (!db.is_object() || !db.contains("entries") || !db["entries"].is_array())
        throw InputError("GEMM tuning database " + name + ": expected an object with an \"entries\" array");
    std::vector<GemmTuningEntry> out;
    for (std::size_t i = 0; i < db["entries"].size(); ++i) {
        const json& j = db["entries"][i];
        const std::string where = "GEMM tuning database " + name + ", entry " + std::to_string(i);
        if (!j.is_object() || !j.contains("match") || !j["match"].is_object() || !j.contains("params") ||
            !j["params"].is_string())
            throw InputError(where + ": expected {\"match\": {...}, \"params\": \"MR,VW,...\"}");
        GemmTuningEntry e;
        for (const auto& [key, value] : j["match"].items()) {
            std::string* f = field(e, key);
            if (!f) {
                std::string known;
                for (const char* k : kMatchKeys) known += std::string(known.empty() ? "" : ", ") + k;
                throw InputError(where + ": unknown match key '" + key + "' (" + known + ")");
            }
            if (!value.is_string() || value.get<std::string>().empty())
                throw InputError(where + ": match." + key + " must be a non-empty string");
            *f = value.get<std::string>();
        }
        if (!e.type.empty() && e.type != "cpu" && e.type != "gpu" && e.type != "other")
            throw InputError(where + ": match.type must be cpu, gpu or other, not '" + e.type + "'");
        if (!e.vector_width.empty() && e.vector_width != "1" && e.vector_width != "2" && e.vector_width != "4" &&
            e.vector_width != "8" && e.vector_width != "16")
            throw InputError(where + ": match.vector_width must be \"1\", \"2\", \"4\", \"8\" or \"16\", not '" +
                             e.vector_width + "'");
        try {
            e.params = parse_gemm_params(j["params"].get<std::string>());
        } catch (const InputError& err) {
            throw InputError(where + ": " + err.what());
        }
        if (j.contains("conv_params")) {
            try {
                if (!j["conv_params"].is_string())
                    throw InputError("conv_params must be a string \"MR,VW,...\" or \"im2col\"");
                if (j["conv_params"].get<std::string>() == "im2col") {
                    e.conv_im2col = true;
                } else {
                    e.conv_params = parse_gemm_params(j["conv_params"].get<std::string>());
                }
                if (e.conv_params && e.conv_params->kwg > 0)
                    throw InputError("conv_params: the implicit convolution has no local-memory variant (KWG 0)");
            } catch (const InputError& err) {
                throw InputError(where + ": " + err.what());
            }
        }
        if (j.contains("note") && j["note"].is_string()) e.note = j["note"].get<std::string>();
        for (const auto& prev : out)
            if (match_json(prev) == match_json(e)) throw InputError(where + ": a second entry with the same match");
        out.push_back(std::move(e));
    }
    return out;
}

const std::vector<GemmTuningEntry>& gemm_tuning_database() {
    static const std::vector<GemmTuningEntry> db = [] {
        for (std::size_t i = 0; i < kEmbeddedKernelCount; ++i)
            if (std::string(kEmbeddedKernels[i].name) == "gemm_tuning")
                return parse_gemm_tuning(std::string(kEmbeddedKernels[i].source, kEmbeddedKernels[i].size),
                                         "kernels/gemm_tuning.json");
        throw Error("GEMM tuning database: kernels/gemm_tuning.json was not embedded at build time");
    }();
    return db;
}

const GemmTuningEntry* find_gemm_tuning(const std::vector<GemmTuningEntry>& db, const DeviceInfo& info) {
    const GemmTuningEntry* best = nullptr;
    for (const auto& e : db)
        if (e.matches(info) && (!best || e.specificity() > best->specificity())) best = &e;
    return best;
}

GemmParams gemm_params_for(const DeviceInfo& info) {
    if (const char* e = std::getenv("NGI_GEMM"); e && *e) return parse_gemm_params(e);
    if (const GemmTuningEntry* t = find_gemm_tuning(gemm_tuning_database(), info)) return t->params;
    return GemmParams{};  // unreachable with the shipped database: it has a default entry (tested)
}

std::optional<GemmParams> conv_params_for(const DeviceInfo& info, const GemmParams& gemm) {
    if (const char* e = std::getenv("NGI_CONV_GEMM"); e && *e) {
        GemmParams p = parse_gemm_params(e);
        if (p.kwg > 0) throw InputError(std::string("NGI_CONV_GEMM='") + e + "': the implicit convolution has no "
                                        "local-memory variant (KWG must be 0)");
        return p;
    }
    if (const GemmTuningEntry* t = find_gemm_tuning(gemm_tuning_database(), info)) {
        if (t->conv_im2col) return std::nullopt;
        if (t->conv_params) return *t->conv_params;
    }
    return gemm;
}

std::string gemm_tuning_with(const std::string& json_text, const GemmTuningEntry& entry) {
    json db = json::parse(json_text);
    parse_gemm_tuning(json_text, "(the database being updated)");  // refuse to extend a broken file
    const json key = match_json(entry);
    json updated = json::array();
    bool replaced = false;
    for (auto& j : db["entries"]) {
        if (j["match"] == key) {
            j["params"] = entry.params.to_string();
            j["note"] = entry.note;
            replaced = true;
        }
        updated.push_back(j);
    }
    if (!replaced) updated.push_back({{"match", key}, {"params", entry.params.to_string()}, {"note", entry.note}});
    db["entries"] = updated;
    return db.dump(2) + "\n";
}

}  // namespace ngi::detail
