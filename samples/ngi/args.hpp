// A small, strict command-line parser for the ngi sample: "--name value" / "--name=value" options, "--flag"
// switches, positionals. Every mistake is a UsageError naming the option (exit code 2): an unknown or repeated
// option, a missing value, a number that is not entirely a number, not finite, or out of range.
#pragma once
#include <charconv>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace ngi_cli {

struct UsageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

class Args {
public:
    // flags: option names that take no value (e.g. "profile"); options: names that take one. Anything else
    // starting with "--" is an error, so a mistyped option is never silently ignored.
    Args(int argc, char** argv, int first, const std::set<std::string>& flags, const std::set<std::string>& options) {
        for (int i = first; i < argc; ++i) {
            const std::string a = argv[i];
            if (a.rfind("--", 0) != 0 || a == "--") {
                positional_.push_back(a);
                continue;
            }
            std::string name = a.substr(2), value;
            const auto eq = name.find('=');
            if (eq != std::string::npos) {
                value = name.substr(eq + 1);
                name.resize(eq);
            }
            if (flags.count(name)) {
                if (eq != std::string::npos) throw UsageError("option --" + name + " takes no value");
                value = std::string(1, '1');  // not = "1": GCC 12 -Wrestrict false positive (PR105329)
            } else if (options.count(name)) {
                if (eq == std::string::npos) {
                    if (i + 1 >= argc) throw UsageError("option --" + name + " needs a value");
                    value = argv[++i];
                }
            } else {
                throw UsageError("unknown option --" + name);
            }
            if (!options_.emplace(name, value).second) throw UsageError("option --" + name + " given twice");
        }
    }
    bool has(const std::string& name) const { return options_.count(name) > 0; }
    std::string get(const std::string& name, const std::string& fallback = "") const {
        auto it = options_.find(name);
        return it == options_.end() ? fallback : it->second;
    }
    std::string require(const std::string& name) const {
        if (!has(name)) throw UsageError("missing required option --" + name);
        if (get(name).empty()) throw UsageError("option --" + name + " needs a non-empty value");
        return get(name);
    }
    const std::vector<std::string>& positional() const { return positional_; }

    // A whole decimal integer in [lo, hi]; no sign games, no trailing characters, no overflow.
    int integer(const std::string& name, int fallback, int lo, int hi) const {
        if (!has(name)) return fallback;
        return parse_int(get(name), "--" + name, lo, hi);
    }
    // A whole finite decimal number in [lo, hi] (so "nan", "inf", "1e999", "3x" are refused).
    double real(const std::string& name, double fallback, double lo, double hi) const {
        if (!has(name)) return fallback;
        const std::string& s = options_.at(name);
        double v = 0;
        const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (s.empty() || ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v) || v < lo || v > hi)
            throw UsageError("--" + name + " needs a number in " + num(lo) + ".." + num(hi) + ", got '" + s + "'");
        return v;
    }

    static int parse_int(const std::string& s, const std::string& what, int lo, int hi) {
        long long v = 0;
        const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (s.empty() || ec != std::errc() || end != s.data() + s.size() || v < lo || v > hi)
            throw UsageError(what + " needs an integer in " + std::to_string(lo) + ".." + std::to_string(hi) +
                             ", got '" + s + "'");
        return int(v);
    }

private:
    static std::string num(double v) {
        char b[32];
        const auto r = std::to_chars(b, b + sizeof b, v);
        return std::string(b, r.ptr);
    }
    std::map<std::string, std::string> options_;
    std::vector<std::string> positional_;
};

// Commands without positional arguments refuse stray words (often a forgotten "--" or a missing option name).
inline void no_positionals(const Args& args) {
    if (!args.positional().empty()) throw UsageError("unexpected argument '" + args.positional()[0] + "'");
}

}  // namespace ngi_cli
