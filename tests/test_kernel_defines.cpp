// Every constant the host and the kernels share is defined once, on the host, and reaches the kernels as build
// options (runtime/kernel_defines.hpp): the options' formatting, the #error guard of every kernel file that needs
// them, and no comment left anywhere in the sources that asks to keep two copies of a value equal.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "ngi/error.hpp"
#include "runtime/kernel_defines.hpp"
#include "test_support.hpp"

using namespace ngi;
using namespace ngi::detail;

TEST_CASE("kernel defines: floats as exact OpenCL C literals, ints, lists", "[runtime]") {
    CHECK(define("A", 3) == "-DA=3");
    CHECK(define("A", -7) == "-DA=-7");
    CHECK(define("F", 5000.0f) == "-DF=5000.0f");
    CHECK(define("F", 0.25f) == "-DF=0.25f");
    CHECK(define("F", 1.0e30f) == "-DF=1e+30f");
    CHECK(define("F", 0.2126f) == "-DF=0.2126f");
    // Every float reads back as itself (the kernel computes with the host's bits).
    for (float v : {1.0e-3f, 0.1f, 3.4028235e38f, 1.17549435e-38f, 65504.0f, 0.7152f, -2.5e-7f}) {
        const std::string d = define("V", v);
        const std::string lit = d.substr(4, d.size() - 5);  // between "-DV=" and 'f'
        INFO(d);
        CHECK(std::strtof(lit.c_str(), nullptr) == v);
    }
    CHECK_THROWS_AS(define("F", std::numeric_limits<float>::infinity()), Error);
    CHECK_THROWS_AS(define("F", std::numeric_limits<float>::quiet_NaN()), Error);
    const int list[4] = {0, -1, 1, 0};
    CHECK(define_list("L", list) == "-DL=0,-1,1,0");
    CHECK(join_defines({"-DA=1", "", "-DB=2"}) == "-DA=1 -DB=2");
}

TEST_CASE("kernel defines: every kernel file that needs host constants refuses to build without them", "[runtime]") {
    // Each program built with no options must fail in its #error guard, which names the missing value: a kernel
    // never runs with a default that could differ from the host's.
    struct Case {
        const char* program;
        const char* kernel;
        const char* names;  // what the build log must mention
    };
    const Case cases[] = {
        {"elementwise", "activate_inplace", "activation_defines"},
        {"mlp", "mlp_fused", "mlp_defines"},
        {"jbu", "jbu_upsample", "JBU_MAX_RADIUS"},
        {"max_pool", "max_pool2d", "MAX_POOL_LOCAL"},
        {"pad2d", "pad2d", "PAD2D_LOCAL"},
        {"resize", "resize_bilinear", "RESIZE_LOCAL"},
        {"voxel_ltf", "ltf_energy", "LTF_R_MIN"},
        {"voxel_ltf", "ltf_energy", "luminance_defines"},  // luminance.cl, listed before voxel_ltf.cl
        {"probe_shade", "probe_shade", "probe_shade_defines"},
        {"gbuffer", "preprocess_gbuffer", "preprocess_defines"},
        {"compose", "tonemap", "compose_defines"},
        {"compose", "tonemap", "tonemap_defines"},  // tonemap.cl, listed before compose.cl
        {"display", "display_compose", "tonemap_defines"},
        {"neural_gi", "neural_gi_inputs", "NGI_RADIANCE_MAX"},
        {"ssgi", "ssgi_gather", "ssgi_defines"},
        {"voxel_compact", "vc_flag", "VC_LOCAL"},
        {"bvh", "bvh_trace_rays", "bvh_defines"},
        // The tracer's programs: each file's guard names what it needs (luminance.cl: luminance_defines, scene.cl:
        // RAY_OFFSET, lighting.cl and patch_weights.cl: the light layout).
        {"pathtrace", "pt_features", "luminance_defines"},
        {"pathtrace", "pt_features", "RAY_OFFSET"},
        {"ao_geometry", "pt_ao", "RAY_OFFSET"},
        {"voxel_field", "vf_sh", "light layout"},
    };
    for (const Case& c : cases) {
        INFO(c.program);
        try {
            test::ctx().kernel(c.program, c.kernel, "");
            FAIL("built without its host constants");
        } catch (const ClError& e) {
            const std::string what = e.what();
            INFO(what);
            // The build log is the driver's: PoCL and rusticl print the #error text. Others may not; the build
            // failing at all is what matters there.
            if (test::ctx().info().platform_name == "Portable Computing Language") CHECK(what.find(c.names) != std::string::npos);
        }
    }
}

TEST_CASE("sources: no comment asks to keep two copies of a constant equal", "[runtime]") {
    // Constants are defined once (on the host, passed to the kernels as build options, read by Python from the
    // generated ngi._constants), so no comment may ask a reader to keep two copies equal.
    namespace fs = std::filesystem;
    const fs::path root = NGI_SOURCE_DIR;
    const std::string keep = std::string("keep in") + " sync", kept = std::string("kept in") + " sync";
    const std::vector<std::string> exts = {".cpp", ".hpp", ".h", ".c", ".cl", ".py", ".cmake", ".sh", ".in", ".txt"};
    std::vector<std::string> found;
    int scanned = 0;
    for (auto it = fs::recursive_directory_iterator(root, fs::directory_options::skip_permission_denied);
         it != fs::recursive_directory_iterator(); ++it) {
        const fs::path& p = it->path();
        const std::string name = p.filename().string();
        if (it->is_directory()) {
            // Build trees, caches, VCS data: not sources.
            if (name.rfind("build", 0) == 0 || name[0] == '.' || name == "__pycache__" || name == "third_party")
                it.disable_recursion_pending();
            continue;
        }
        if (!it->is_regular_file()) continue;
        if (std::find(exts.begin(), exts.end(), p.extension().string()) == exts.end()) continue;
        std::ifstream f(p, std::ios::binary);
        std::stringstream ss;
        ss << f.rdbuf();
        std::string text = ss.str();
        std::transform(text.begin(), text.end(), text.begin(), [](unsigned char ch) { return char(std::tolower(ch)); });
        ++scanned;
        for (const std::string& phrase : {keep, kept})
            for (std::size_t at = text.find(phrase); at != std::string::npos; at = text.find(phrase, at + 1)) {
                const std::size_t line = std::size_t(std::count(text.begin(), text.begin() + std::ptrdiff_t(at), '\n')) + 1;
                found.push_back(fs::relative(p, root).string() + ":" + std::to_string(line));
            }
    }
    INFO("scanned " << scanned << " files under " << root.string());
    CHECK(scanned > 100);
    CHECK(found == std::vector<std::string>{});
}
