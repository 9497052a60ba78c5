#include "plan_file.hpp"

#include <filesystem>
#include <set>
#include <vector>
#include <nlohmann/json.hpp>

#include "ngi/error.hpp"
#include "ngi/files.hpp"
#include "ngi/pipeline.hpp"

namespace ngi_cli {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

[[noreturn]] void fail(const std::string& path, const std::string& what) {
    throw ngi::InputError("plan " + path + ": " + what + " (plans are written by `python3 -m ngi.plan`)");
}

PlanRung read_rung(const json& j, const std::string& where, const std::string& path) {
    if (!j.is_object()) fail(path, where + " must be an object");
    auto text = [&](const char* key, bool required) -> std::string {
        if (!j.contains(key)) {
            if (required) fail(path, where + " has no '" + key + "'");
            return "";
        }
        if (!j[key].is_string() || j[key].get<std::string>().empty())
            fail(path, where + "." + key + " must be a non-empty string");
        return j[key].get<std::string>();
    };
    PlanRung r;
    r.name = text("rung", true);
    if (!j.contains("model")) fail(path, where + " has no 'model'");
    if (j["model"].is_null()) {  // the direct-light rung: no network
        if (j.contains("n") && j["n"].is_number_integer()) r.n = j["n"].get<int>();
        if (r.n < 1 || r.n > 8192) fail(path, where + ".n must be an integer face size in 1..8192");
        return r;
    }
    r.model = text("model", true);
    r.bn_mode = text("bn_mode", false);
    if (!r.bn_mode.empty() && r.bn_mode != "running" && r.bn_mode != "per_image")
        fail(path, where + ".bn_mode must be \"running\" or \"per_image\", got \"" + r.bn_mode + "\"");
    if (!j.contains("n") || !j["n"].is_number_integer() || j["n"].get<long long>() < 1 ||
        j["n"].get<long long>() > 8192)
        fail(path, where + ".n must be an integer face size in 1..8192");
    r.n = j["n"].get<int>();
    const fs::path model = fs::path(r.model).is_absolute() ? fs::path(r.model) : fs::path(path).parent_path() / r.model;
    std::error_code ec;
    const fs::file_type type = fs::status(model, ec).type();  // links followed, as the loader opens the file
    if (type != fs::file_type::regular) {
        const char* what = type == fs::file_type::not_found || type == fs::file_type::none ? "does not exist"
                           : type == fs::file_type::directory                                ? "is a directory"
                           : type == fs::file_type::fifo                                     ? "is a FIFO, not a regular file"
                           : type == fs::file_type::character || type == fs::file_type::block
                               ? "is a device, not a regular file"
                               : "is not a regular file";
        fail(path, where + ".model: " + model.string() + " " + what + " (rung " + r.name + ")");
    }
    r.model = model.string();
    return r;
}

}  // namespace

Plan Plan::load(const std::string& path) { return parse(ngi::read_input_file(path, "plan"), path); }

Plan Plan::parse(const std::string& text, const std::string& path) {
    // A repeated key is refused: nlohmann keeps the last one silently, so {"model": A, ..., "model": B} ran B.
    // (The library's detail::parse_json_unique_keys does the same for its own files; the CLI sees public headers only.)
    std::vector<std::set<std::string>> keys;  // the keys of each object being parsed, innermost last
    std::string repeated;
    const json::parser_callback_t unique = [&](int, json::parse_event_t event, json& parsed) {
        if (event == json::parse_event_t::object_start) keys.emplace_back();
        else if (event == json::parse_event_t::object_end && !keys.empty()) keys.pop_back();
        else if (event == json::parse_event_t::key && !keys.empty() && !keys.back().insert(parsed.get<std::string>()).second &&
                 repeated.empty())
            repeated = parsed.get<std::string>().substr(0, 80);
        return true;
    };
    json j;
    try {
        j = json::parse(text, unique);
    } catch (const json::exception& e) {
        fail(path, std::string("not valid JSON: ") + e.what());
    }
    if (!repeated.empty()) fail(path, "the key '" + repeated + "' appears twice in one object; say it once");
    if (!j.is_object() || !j.contains("format") || j["format"] != "ngi-plan")
        fail(path, "not a plan (\"format\": \"ngi-plan\")");
    if (!j.contains("version") || j["version"] != 1) fail(path, "unsupported version (this ngi reads version 1)");
    Plan p;
    p.path = path;
    p.rung = read_rung(j, "the top level", path);
    if (j.contains("switch") && !j["switch"].is_null()) {
        const json& s = j["switch"];
        if (!s.is_object() || !s.contains("below_outside_light_share") ||
            !s["below_outside_light_share"].is_number() || !(s["below_outside_light_share"].get<double>() >= 0.0) ||
            !(s["below_outside_light_share"].get<double>() <= 1.0))
            fail(path, "switch.below_outside_light_share must be a number in [0, 1]");
        p.fallback = Switch{s["below_outside_light_share"].get<double>(), read_rung(s, "switch", path)};
        if (p.fallback->rung.n != p.rung.n)
            fail(path, "the switch's rung runs at N = " + std::to_string(p.fallback->rung.n) + ", the plan's at " +
                           std::to_string(p.rung.n) + ": one frame cannot feed both");
    }
    if (j.contains("guard") && !j["guard"].is_null()) {  // null: no guard, as for "switch"
        const json& g = j["guard"];
        if (!g.is_object()) fail(path, "guard must be an object {\"max_indirect_share\": T}");
        for (const auto& item : g.items())  // a misspelt key would silently disable the guard
            if (item.key() != "max_indirect_share")
                fail(path, "guard has an unknown key '" + item.key() + "' (it takes max_indirect_share only)");
        if (!g.contains("max_indirect_share")) fail(path, "guard has no 'max_indirect_share'");
        const json& t = g["max_indirect_share"];
        // A JSON number is finite; 0 would send every lit frame to direct light, above 1 the guard never acts.
        if (!t.is_number() || !(t.get<double>() > 0.0) || !(t.get<double>() <= 1.0))
            fail(path, "guard.max_indirect_share must be a number with 0 < T <= 1, got " + t.dump());
        p.guard = Guard{t.get<double>()};
    }
    return p;
}

const PlanRung& Plan::choose(const ngi::Frame& frame, double& share) const {
    if (frame.n != rung.n)
        throw ngi::InputError("plan " + path + ": rung " + rung.name + " runs at face size " + std::to_string(rung.n) +
                              ", the frame has " + std::to_string(frame.n) + " (render the frame at --face " +
                              std::to_string(rung.n) + ")");
    share = -1.0;
    if (!fallback) return rung;
    share = ngi::outside_light_share(frame);
    return share < fallback->below ? fallback->rung : rung;
}

}  // namespace ngi_cli
