// The perf/ benchmarks' minimal argument reading ("--name value" pairs, comma lists): shared by render_bench and
// bench_bvh, whose options are few and all optional (ngi_bench uses CLI11 for its subcommands).
#pragma once
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

namespace ngi_perf {

// The value after `name` on the command line, or `fallback`.
inline std::string arg(int argc, char** argv, const char* name, const std::string& fallback) {
    for (int i = 1; i + 1 < argc; ++i)
        if (!std::strcmp(argv[i], name)) return argv[i + 1];
    return fallback;
}

// "a,b,,c" -> {"a", "b", "c"}.
inline std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    for (std::string item; std::getline(ss, item, ',');)
        if (!item.empty()) out.push_back(item);
    return out;
}

}  // namespace ngi_perf
