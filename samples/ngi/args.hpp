// A small command-line parser for the ngi sample: "--name value" options, "--flag" switches, positionals.
#pragma once
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace ngi_cli {

struct UsageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

class Args {
public:
    // flags: option names that take no value (e.g. "profile").
    Args(int argc, char** argv, int first, const std::set<std::string>& flags) {
        for (int i = first; i < argc; ++i) {
            std::string a = argv[i];
            if (a.rfind("--", 0) == 0) {
                std::string name = a.substr(2);
                if (auto eq = name.find('='); eq != std::string::npos) {
                    options_[name.substr(0, eq)] = name.substr(eq + 1);
                } else if (flags.count(name)) {
                    options_[name] = std::string(1, '1');  // not = "1": GCC 12 -Wrestrict false positive (PR105329)
                } else {
                    if (i + 1 >= argc) throw UsageError("option --" + name + " needs a value");
                    options_[name] = argv[++i];
                }
            } else {
                positional_.push_back(a);
            }
        }
    }
    bool has(const std::string& name) const { return options_.count(name) > 0; }
    std::string get(const std::string& name, const std::string& fallback = "") const {
        auto it = options_.find(name);
        return it == options_.end() ? fallback : it->second;
    }
    std::string require(const std::string& name) const {
        if (!has(name)) throw UsageError("missing required option --" + name);
        return get(name);
    }
    const std::vector<std::string>& positional() const { return positional_; }

private:
    std::map<std::string, std::string> options_;
    std::vector<std::string> positional_;
};

}  // namespace ngi_cli
