// Whole MLP model files against PyTorch (the oracle): tests/parity/make_mlp_parity.py builds MLPs with random
// weights (seed 001's sizes, both encoding orders, a width that takes the dense path, fp16 weights) and stores
// PyTorch's float64 output. ngi must reproduce it on the fused path and on the dense path.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "ngi/model.hpp"
#include "ops/mlp.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

TEST_CASE("mlp model files match PyTorch on the fused and the dense path", "[model][parity][mlp]") {
    const fs::path dir = ngi::test::python_oracle_data("make_mlp_parity.py", "mlp_parity");
    nlohmann::json cases;
    std::ifstream(dir / "cases.json") >> cases;
    REQUIRE(cases.size() >= 4);
    double worst_abs = 0;
    for (const auto& c : cases) {
        const ngi::Tensor x = ngi::read_npy((dir / c["input"].get<std::string>()).string());
        const ngi::Tensor want = ngi::read_npy((dir / c["expected"].get<std::string>()).string());
        std::vector<std::string> paths = {"dense"};
        if (c["widest"].get<int>() <= ngi::detail::kFusedMlpMaxWidth) paths.push_back("fused");
        for (const std::string& path : paths) {
            CAPTURE(c["name"].get<std::string>(), path);
            ngi::ModelOptions opt;
            opt.mlp_path = path;
            ngi::Model m = ngi::Model::load(ngi::test::device(), (dir / c["model"].get<std::string>()).string(), opt);
            const ngi::Tensor y = m.run(x);
            REQUIRE(y.shape == want.shape);
            // float32 against float64: sums of <= 200 products of O(1) terms, sin/cos of arguments <= 25,
            // through 3 layers: ~1e-5 observed; 1e-4 absolute + 1e-4 relative leaves room for other devices' sin.
            REQUIRE(ngi::test::worst_ratio(y.data, want.data, 1e-4, 1e-4) <= 1.0);
            worst_abs = std::max(worst_abs, ngi::test::max_abs_diff(y.data, want.data));
        }
    }
    WARN("mlp parity: largest |ngi - PyTorch float64| over all cases and paths: " << worst_abs);
}
