// Seed 002's network (family "neural_gi") against PyTorch: tests/parity/make_neural_gi_parity.py exports
// ngi.neural_gi.NeuralGI models with random weights (the paper's 8 x 256 MLP with re-injection on a small U-Net and
// F16 weights; narrow odd widths; no re-injection with running batch-norm statistics) and stores PyTorch's float64
// indirect light. ngi runs the whole network (encoding, U-Net, MLP, exp decoding) as one graph.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "ngi/model.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;

namespace {

fs::path parity_dir() { return ngi::test::python_oracle_data("make_neural_gi_parity.py", "neural_gi_parity"); }

nlohmann::json parity_cases() {
    nlohmann::json j;
    std::ifstream(parity_dir() / "cases.json") >> j;
    return j;
}

}  // namespace

TEST_CASE("neural_gi model files match PyTorch (encoding, U-Net buffer, re-injected MLP, exp)", "[model][parity][neural_gi]") {
    const fs::path dir = parity_dir();
    const nlohmann::json cases = parity_cases()["cases"];
    REQUIRE(cases.size() >= 3);
    double worst = 0;
    for (const auto& c : cases) {
        CAPTURE(c["name"].get<std::string>());
        const ngi::Tensor x = ngi::read_npy((dir / c["input"].get<std::string>()).string());
        const ngi::Tensor want = ngi::read_npy((dir / c["expected"].get<std::string>()).string());
        ngi::Model m = ngi::Model::load(ngi::test::device(), (dir / c["model"].get<std::string>()).string());
        CHECK(m.config().family == "neural_gi");
        ngi::RunInfo info;
        const ngi::Tensor y = m.run(x, &info);
        REQUIRE(y.shape == want.shape);
        CHECK(info.sanitized_inputs == 0);
        // The output is exp(raw): its relative error is the raw output's absolute error. float32 against float64
        // through the U-Net (per-image batch norm at every level), the encoding (sin/cos of arguments up to 256 pi:
        // float32 rounding of the argument alone is ~2e-5) and up to 650-term sums in 8 layers: observed 8.5e-5 on
        // PoCL (2026-11-28). 2e-4 relative is the figure README.md states: 2.3x the observation, for another device's
        // sin/cos and exp (OpenCL 1.2 allows 4 ulp for sin/cos, 3 for exp; the argument's own rounding dominates).
        double case_worst = 0;
        for (std::size_t i = 0; i < y.data.size(); ++i) {
            REQUIRE(std::isfinite(y.data[i]));
            CHECK(y.data[i] >= 0.0f);
            case_worst = std::max(case_worst, std::abs(double(y.data[i]) - want.data[i]) / want.data[i]);
        }
        CHECK(case_worst < 2e-4);
        worst = std::max(worst, case_worst);
    }
    WARN("neural_gi parity: largest relative |ngi - PyTorch float64| of the indirect light: " << worst);
}

TEST_CASE("neural_gi: hostile inputs are sanitized, the output stays finite and non-negative", "[model][neural_gi]") {
    const fs::path dir = parity_dir();
    const nlohmann::json c = parity_cases()["cases"][1];
    ngi::Model m = ngi::Model::load(ngi::test::device(), (dir / c["model"].get<std::string>()).string());
    ngi::Tensor x = ngi::read_npy((dir / c["input"].get<std::string>()).string());
    x.data[0] = std::numeric_limits<float>::quiet_NaN();
    x.data[5] = std::numeric_limits<float>::infinity();
    x.data[x.data.size() / 2] = 3.0e38f;  // log1p(direct) of a saturated value would be 88.7: beyond the range
    x.data[x.data.size() - 1] = -1.0e30f;
    ngi::RunInfo info;
    const ngi::Tensor y = m.run(x, &info);
    CHECK(info.sanitized_inputs == 4);
    for (float v : y.data) {
        REQUIRE(std::isfinite(v));
        REQUIRE(v >= 0.0f);
    }
    // Sizes the U-Net cannot take are refused with the rule.
    const ngi::Tensor odd({1, 18, 32, 48});
    CHECK_THROWS_WITH(m.run(odd), Contains("multiple of 2^num_downs = 32"));
    const ngi::Tensor wrong({1, 12, 32, 32});
    CHECK_THROWS_WITH(m.run(wrong), Contains("expected [1, 18, H, W]"));
}

TEST_CASE("neural_gi: broken files are refused with the field or tensor named", "[model][neural_gi]") {
    const fs::path dir = parity_dir();
    const nlohmann::json bad = parity_cases()["bad"];
    REQUIRE(bad.size() >= 8);
    for (const auto& b : bad) {
        const std::string file = (dir / b["model"].get<std::string>()).string();
        CAPTURE(file);
        CHECK_THROWS_WITH(ngi::Model::load(ngi::test::device(), file),
                          Contains(b["expect"].get<std::string>()) && Contains(b["model"].get<std::string>()));
    }
}
