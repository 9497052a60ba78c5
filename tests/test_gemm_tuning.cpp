// The GEMM tuning database (ops/gemm_tuning.hpp, kernels/gemm_tuning.json): the lookup order (exact device >
// vendor > type > default), the checks on a broken database, the shipped database, and the tuner's write-back.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "ngi/error.hpp"
#include "ops/gemm_selfcheck.hpp"
#include "ops/gemm_tuning.hpp"
#include "test_support.hpp"

using namespace ngi;
using namespace ngi::detail;

namespace {

DeviceInfo device_info(const std::string& platform, const std::string& vendor, const std::string& name,
                       const std::string& driver, bool gpu) {
    DeviceInfo i;
    i.platform_name = platform;
    i.vendor = vendor;
    i.name = name;
    i.driver_version = driver;
    i.is_gpu = gpu;
    i.is_cpu = !gpu;
    return i;
}

const char* kDb = R"({"entries": [
  {"match": {}, "params": "1,1,1,1,1,1"},
  {"match": {"type": "gpu"}, "params": "4,4,1,1,16,16"},
  {"match": {"vendor": "ACME", "type": "gpu"}, "params": "8,4,1,1,8,8"},
  {"match": {"vendor": "ACME", "device": "Rocket 9000"}, "params": "8,4,2,1,8,8"},
  {"match": {"vendor": "ACME", "device": "Rocket 9000", "driver": "1.2.3"}, "params": "8,4,2,4,8,8,0"},
  {"match": {"type": "cpu"}, "params": "6,16,2,1,1,4"},
  {"match": {"type": "cpu", "vector_width": "8"}, "params": "4,16,1,4,1,4"},
  {"match": {"platform": "rusticl", "type": "cpu"}, "params": "6,16,2,1,1,4,0"}
]})";

std::string lookup(const std::vector<GemmTuningEntry>& db, const DeviceInfo& info) {
    const GemmTuningEntry* e = find_gemm_tuning(db, info);
    return e ? e->params.to_string() : "none";
}

}  // namespace

TEST_CASE("GEMM tuning database: the most specific matching entry wins", "[gemm][tuning]") {
    const auto db = parse_gemm_tuning(kDb, "test");
    REQUIRE(db.size() == 8);
    CHECK(lookup(db, device_info("P", "ACME", "Rocket 9000", "1.2.3", true)) == "8,4,2,4,8,8,0");  // exact
    CHECK(lookup(db, device_info("P", "ACME", "Rocket 9000", "2.0", true)) == "8,4,2,1,8,8,1");    // other driver
    CHECK(lookup(db, device_info("P", "ACME", "Rocket 5", "1.2.3", true)) == "8,4,1,1,8,8,1");     // vendor + type
    CHECK(lookup(db, device_info("P", "Other", "X", "1", true)) == "4,4,1,1,16,16,1");            // type
    CHECK(lookup(db, device_info("P", "Other", "X", "1", false)) == "6,16,2,1,1,4,1");            // cpu
    // A CPU of 8-float registers (AVX2) takes the vector-width entry; one of 16 (AVX-512) the type's.
    DeviceInfo avx2 = device_info("P", "Other", "X", "1", false), avx512 = avx2;
    avx2.native_float_vector_width = 8;
    avx512.native_float_vector_width = 16;
    CHECK(lookup(db, avx2) == "4,16,1,4,1,4,1");
    CHECK(lookup(db, avx512) == "6,16,2,1,1,4,1");
    // A platform entry outranks a vector width: rusticl keeps its own entry on an AVX2 machine.
    DeviceInfo rusticl_avx2 = device_info("rusticl", "Other", "X", "1", false);
    rusticl_avx2.native_float_vector_width = 8;
    CHECK(lookup(db, rusticl_avx2) == "6,16,2,1,1,4,0");
    DeviceInfo accel = device_info("P", "Other", "X", "1", false);
    accel.is_cpu = false;
    CHECK(lookup(db, accel) == "1,1,1,1,1,1,1");                                                   // default
}

TEST_CASE("GEMM tuning database: broken entries are refused with the entry named", "[gemm][tuning]") {
    auto refused = [](const std::string& text, const std::string& what) {
        try {
            parse_gemm_tuning(text, "db.json");
        } catch (const InputError& e) {
            CHECK_THAT(e.what(), Catch::Contains("db.json") && Catch::Contains(what));
            return;
        }
        FAIL("accepted: " << text);
    };
    refused("{", "not valid JSON");
    refused(R"({"entries": 3})", "entries");
    refused(R"({"entries": [{"match": {"colour": "red"}, "params": "1,1,1,1,1,1"}]})", "unknown match key 'colour'");
    refused(R"({"entries": [{"match": {"type": "fpga"}, "params": "1,1,1,1,1,1"}]})", "cpu, gpu or other");
    refused(R"({"entries": [{"match": {}, "params": "3,3,1,1,1,1"}]})", "entry 0");  // VW 3 is no vector width
    refused(R"({"entries": [{"match": {}, "params": "1,1,1,1,1,1"}, {"match": {}, "params": "4,4,1,1,1,1"}]})",
            "same match");
    refused(R"({"entries": [{"match": {"vendor": ""}, "params": "1,1,1,1,1,1"}]})", "non-empty");
    refused(R"({"entries": [{"match": {"vector_width": "3"}, "params": "1,1,1,1,1,1"}]})", "vector_width");
    refused(R"({"entries": [{"match": {"vector_width": 8}, "params": "1,1,1,1,1,1"}]})", "non-empty string");
    refused(R"({"entries": [{"match": {}, "params": "1,1,1,1,1,1", "conv_params": "4,4,1,1,8,8,1,16"}]})",
            "no local-memory variant");
    refused(R"({"entries": [{"match": {}, "params": "1,1,1,1,1,1", "conv_params": 8}]})", "conv_params");
    refused(R"({"entries": [{"match": {}, "params": "1,1,1,1,1,1", "conv_params": "8,3,1,1,1,1"}]})", "entry 0");
}

TEST_CASE("GEMM tuning database: the implicit convolution's knob set, where an entry has one", "[gemm][tuning]") {
    const auto db = parse_gemm_tuning(R"({"entries": [
      {"match": {}, "params": "1,1,1,1,1,1"},
      {"match": {"type": "cpu"}, "params": "6,16,2,1,1,4", "conv_params": "8,16,3,1,1,4"}]})", "test");
    REQUIRE(db.size() == 2);
    CHECK_FALSE(db[0].conv_params.has_value());
    REQUIRE(db[1].conv_params.has_value());
    CHECK(db[1].conv_params->to_string() == "8,16,3,1,1,4,1");
    // The shipped database: this device's selection carries a conv set that passes the same self-check.
    const GemmSelection& sel = gemm_selection(test::ctx());
    INFO("GEMM " << sel.params.to_string() << ", convolution " << (sel.conv_params ? sel.conv_params->to_string() : "im2col"));
    if (sel.conv_params) {
        CHECK(sel.conv_params->kwg == 0);
        CHECK(check_gemm_variant(test::ctx(), *sel.conv_params, gemm_selfcheck_problems()).ok);
    }
    // "im2col" turns the implicit path off for the entry's devices.
    const auto off = parse_gemm_tuning(R"({"entries": [{"match": {}, "params": "1,1,1,1,1,1", "conv_params": "im2col"}]})",
                                       "test");
    CHECK(off[0].conv_im2col);
    CHECK_FALSE(off[0].conv_params.has_value());
}

TEST_CASE("GEMM tuning database: the shipped one parses, has a default, and its choice passes the self-check",
          "[gemm][tuning]") {
    const auto& db = gemm_tuning_database();
    bool has_default = false;
    for (const auto& e : db) has_default |= e.specificity() == 0;
    CHECK(has_default);
    const DeviceInfo& info = test::ctx().info();
    const GemmTuningEntry* e = find_gemm_tuning(db, info);
    REQUIRE(e != nullptr);
    INFO("device " << info.name << " (" << info.platform_name << "): entry " << e->params.to_string() << ", " << e->note);
    const GemmVerdict v = check_gemm_variant(test::ctx(), e->params, gemm_selfcheck_problems());
    CHECK(v.ok);
    if (!std::getenv("NGI_GEMM")) CHECK(gemm_params_for(info) == e->params);
}

TEST_CASE("GEMM tuning database: the tuner's write-back adds or replaces one entry", "[gemm][tuning]") {
    GemmTuningEntry e;
    e.vendor = "ACME";
    e.device = "Rocket 9000";
    e.driver = "1.2.3";
    e.params = parse_gemm_params("2,8,1,1,4,4");
    e.note = "tuned";
    const std::string replaced = gemm_tuning_with(kDb, e);
    auto db = parse_gemm_tuning(replaced, "replaced");
    CHECK(db.size() == 8);
    CHECK(lookup(db, device_info("P", "ACME", "Rocket 9000", "1.2.3", true)) == "2,8,1,1,4,4,1");
    e.driver = "1.2.4";
    db = parse_gemm_tuning(gemm_tuning_with(replaced, e), "added");
    CHECK(db.size() == 9);
    CHECK(lookup(db, device_info("P", "ACME", "Rocket 9000", "1.2.3", true)) == "2,8,1,1,4,4,1");
    CHECK(db.back().note == "tuned");
    CHECK_THROWS_AS(gemm_tuning_with("{\"entries\": [{}]}", e), InputError);
}
