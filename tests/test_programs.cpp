// The table of OpenCL programs (runtime/programs.cpp): every program is common.cl then its files in order, so its
// source - and the disk-cache key hashed from it - covers every file it is built from; every kernel file in the
// tree belongs to a program; unknown names are refused.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "ngi/error.hpp"
#include "runtime/context.hpp"
#include "runtime/embedded_kernels.hpp"
#include "runtime/programs.hpp"

using namespace ngi;
using namespace ngi::detail;

namespace {

std::string embedded_source(std::string_view file) {
    for (std::size_t i = 0; i < kEmbeddedKernelCount; ++i)
        if (file == kEmbeddedKernels[i].name) return std::string(kEmbeddedKernels[i].source, kEmbeddedKernels[i].size);
    FAIL("no embedded kernel file " << file);
    return {};
}

}  // namespace

TEST_CASE("programs: each is common.cl then its files in order, each file whole", "[runtime]") {
    std::set<std::string_view> names;
    for (const ProgramSources& p : programs()) {
        INFO(p.name);
        CHECK(names.insert(p.name).second);  // names are unique
        REQUIRE_FALSE(p.files.empty());
        const std::string source = program_source(p.name);
        std::size_t at = 0;
        std::vector<std::string_view> files = {"common"};
        files.insert(files.end(), p.files.begin(), p.files.end());
        for (std::string_view f : files) {
            INFO(f);
            CHECK(std::count(files.begin(), files.end(), f) == 1);  // no file twice
            const std::string marker = "#line 1 \"" + std::string(f) + ".cl\"\n";
            const std::size_t line = source.find(marker, at);
            REQUIRE(line != std::string::npos);
            const std::string text = embedded_source(f);
            REQUIRE(source.compare(line + marker.size(), text.size(), text) == 0);
            at = line + marker.size() + text.size();
        }
    }
}

TEST_CASE("programs: every kernel file in the tree is in a program", "[runtime]") {
    namespace fs = std::filesystem;
    std::set<std::string> listed = {"common"};
    for (const ProgramSources& p : programs())
        for (std::string_view f : p.files) listed.insert(std::string(f));
    int files = 0;
    for (const fs::directory_entry& e : fs::directory_iterator(fs::path(NGI_SOURCE_DIR) / "kernels")) {
        if (e.path().extension() != ".cl") continue;
        ++files;
        INFO(e.path().filename().string());
        CHECK(listed.count(e.path().stem().string()) == 1);
    }
    CHECK(files == int(listed.size()));  // and every listed file exists
}

TEST_CASE("programs: an unknown program is an error naming it", "[runtime]") {
    CHECK_THROWS_WITH(program_sources("pathtrace+bvh"), Catch::Contains("pathtrace+bvh"));
    CHECK_THROWS_AS(program_source("no_such_program"), Error);
}

TEST_CASE("program cache folder: NGI_CACHE_DIR, else an absolute XDG_CACHE_HOME, else an absolute HOME", "[runtime]") {
    // Saved and restored: the suite itself runs with NGI_CACHE_DIR set.
    struct Saved {
        std::string name, value;
        bool set;
    };
    std::vector<Saved> saved;
    for (const char* name : {"NGI_CACHE_DIR", "XDG_CACHE_HOME", "HOME"}) {
        const char* v = std::getenv(name);
        saved.push_back({name, v ? v : "", v != nullptr});
    }
    const auto put = [](const char* name, const char* value) {
        if (value) setenv(name, value, 1);
        else unsetenv(name);
    };
    put("NGI_CACHE_DIR", "/cache/explicit");
    put("XDG_CACHE_HOME", "/xdg");
    put("HOME", "/u");
    CHECK(cache_dir() == std::filesystem::path("/cache/explicit"));
    put("NGI_CACHE_DIR", nullptr);
    CHECK(cache_dir() == std::filesystem::path("/xdg/ngi"));
    put("XDG_CACHE_HOME", "relative/xdg");  // invalid by the XDG spec: ignored
    CHECK(cache_dir() == std::filesystem::path("/u/.cache/ngi"));
    put("XDG_CACHE_HOME", "");
    put("HOME", "relative-home");
    CHECK(cache_dir() == std::filesystem::temp_directory_path() / "ngi-cache");
    for (const Saved& s : saved) put(s.name.c_str(), s.set ? s.value.c_str() : nullptr);
}
