// JSON for ngi's own config files (dataset configs, model metadata): nlohmann's parser keeps the last of repeated
// keys without a word, so {"n": 64, ..., "n": 8} silently rendered at 8. Library-internal.
#pragma once
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "ngi/error.hpp"

namespace ngi::detail {

// nlohmann::json::parse(text), except that an object repeating a key is an InputError("<what>duplicate key 'k'").
// Malformed JSON still throws nlohmann's parse_error, as parse does (callers turn it into their own message).
inline nlohmann::json parse_json_unique_keys(const std::string& text, const std::string& what) {
    std::vector<std::set<std::string>> open;  // the keys seen so far in each object being parsed, innermost last
    nlohmann::json::parser_callback_t check = [&](int, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
        using E = nlohmann::json::parse_event_t;
        if (event == E::object_start) {
            open.emplace_back();
        } else if (event == E::object_end) {
            if (!open.empty()) open.pop_back();
        } else if (event == E::key && !open.empty()) {
            const std::string key = parsed.get<std::string>();
            if (!open.back().insert(key).second)
                throw InputError(what + "duplicate key '" + key.substr(0, 80) +
                                 "' (JSON parsers keep one of them silently; say it once)");
        }
        return true;
    };
    return nlohmann::json::parse(text, check);
}

}  // namespace ngi::detail
