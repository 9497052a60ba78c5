// Shipped models by name (ngi/model.hpp: model_search_path, model_names, resolve_model): the names of the source
// tree's models/ (this build's fallback), the NGI_MODEL_PATH override, paths passing through, and the errors.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <string>

#include "ngi/error.hpp"
#include "ngi/model.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace {

// Sets (or unsets, nullopt) an environment variable for one scope, restoring the old value after.
class EnvGuard {
public:
    EnvGuard(const char* name, std::optional<std::string> value) : name_(name) {
        if (const char* old = std::getenv(name)) old_ = old;
        if (value) ::setenv(name, value->c_str(), 1);
        else ::unsetenv(name);
    }
    ~EnvGuard() {
        if (old_) ::setenv(name_, old_->c_str(), 1);
        else ::unsetenv(name_);
    }
    EnvGuard(const EnvGuard&) = delete;
    EnvGuard& operator=(const EnvGuard&) = delete;

private:
    const char* name_;
    std::optional<std::string> old_;
};

// A fresh empty folder under the temp directory.
fs::path fresh_dir(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("ngi_model_names_" + name);
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

void write(const fs::path& p, const std::string& text) {
    fs::create_directories(p.parent_path());
    std::ofstream(p) << text;
}

std::map<std::string, std::string> names() {
    std::map<std::string, std::string> m;
    for (const auto& [n, f] : ngi::model_names()) m[n] = f;
    return m;
}

std::string message_of_resolve(const std::string& name) {
    try {
        ngi::resolve_model(name);
    } catch (const ngi::InputError& e) {
        return e.what();
    }
    FAIL("resolve_model('" << name << "') did not throw");
    return "";
}

}  // namespace

TEST_CASE("model names: the shipped models resolve by name from the source tree", "[model_names]") {
    EnvGuard env("NGI_MODEL_PATH", std::nullopt);
    const fs::path models = fs::path(NGI_SOURCE_DIR) / "models";
    const auto m = names();
    // Top-level files, subfolders and zoo.json rungs, each to its own file.
    const std::pair<const char*, const char*> expected[] = {
        {"surround", "surround.safetensors"},
        {"single_view", "single_view.safetensors"},
        {"voxel_sh_set", "voxel_sh_set.safetensors"},
        {"ao_bunny_32x16", "ao_bunny_32x16.safetensors"},
        {"neural_gi_room", "neural_gi/neural_gi_room.safetensors"},
        {"surround_n64_ngf16", "ladder/surround_n64_ngf16.safetensors"},
        {"gi_surround_n64_ngf16", "ladder/gi_surround_n64_ngf16.safetensors"},
        {"shipped_surround_n64_ngf32", "surround.safetensors"},  // a zoo.json rung name for a top-level file
    };
    // Each name maps to its file in one folder of the search path: the source tree's, or an installed copy of the
    // same models (share/ngi/models, which comes first when a package is installed on this machine).
    const auto path = ngi::model_search_path();
    for (const auto& [name, file] : expected) {
        INFO(name);
        REQUIRE(m.count(name) == 1);
        const std::string got = ngi::resolve_model(name);
        CHECK(got == m.at(name));
        bool in_a_folder = false;
        for (const std::string& d : path)
            in_a_folder |= fs::exists(fs::path(d) / file) && fs::equivalent(got, fs::path(d) / file);
        CHECK(in_a_folder);
    }
    // Not names: the direct-light rung (no file) and the batch-norm variants (a name would drop their bn_mode).
    CHECK(m.count("direct_only") == 0);
    CHECK(m.count("surround_n64_ngf16@running") == 0);
    // Every shipped .safetensors file has a name: its stem.
    for (const auto& e : fs::recursive_directory_iterator(models))
        if (e.path().extension() == ".safetensors") {
            INFO(e.path());
            CHECK(m.count(e.path().stem().string()) == 1);
        }
    // The source tree's folder is on the search path.
    bool listed = false;
    for (const std::string& d : path) listed |= fs::equivalent(d, models);
    CHECK(listed);
}

TEST_CASE("model names: paths pass through unchanged", "[model_names]") {
    EnvGuard env("NGI_MODEL_PATH", std::nullopt);
    CHECK(ngi::resolve_model("no/such/dir/model.safetensors") == "no/such/dir/model.safetensors");
    CHECK(ngi::resolve_model("missing.safetensors") == "missing.safetensors");  // Model::load names the missing file
    const std::string here = (fs::path(NGI_SOURCE_DIR) / "models" / "surround.safetensors").string();
    CHECK(ngi::resolve_model(here) == here);
    // An existing file in the working directory wins over a name: a file called "surround" is that file.
    const fs::path d = fresh_dir("cwd");
    const fs::path old = fs::current_path();
    write(d / "surround", "not a model");
    fs::current_path(d);
    const std::string got = ngi::resolve_model("surround");
    fs::current_path(old);
    CHECK(got == "surround");
    fs::remove_all(d);
}

TEST_CASE("model names: NGI_MODEL_PATH comes first and adds names", "[model_names]") {
    const fs::path a = fresh_dir("override_a"), b = fresh_dir("override_b");
    write(a / "surround.safetensors", "x");                       // shadows the shipped surround
    write(b / "deep" / "mine.safetensors", "x");                  // a subfolder's file
    write(b / "zoo.json", R"({"format": "ngi-zoo", "version": 1, "rungs": [
        {"name": "fancy", "file": "deep/mine.safetensors"}, {"name": "none", "file": null},
        {"name": "fancy@running", "file": "deep/mine.safetensors"}]})");
    EnvGuard env("NGI_MODEL_PATH", a.string() + ":" + (a / "does_not_exist").string() + "::" + b.string());
    CHECK(fs::equivalent(ngi::resolve_model("surround"), a / "surround.safetensors"));
    CHECK(fs::equivalent(ngi::resolve_model("mine"), b / "deep" / "mine.safetensors"));
    CHECK(fs::equivalent(ngi::resolve_model("fancy"), b / "deep" / "mine.safetensors"));
    // The shipped names not shadowed still resolve (the source tree comes after the override).
    CHECK(fs::path(ngi::resolve_model("single_view")).filename() == "single_view.safetensors");
    const auto path = ngi::model_search_path();
    REQUIRE(path.size() >= 2);
    CHECK(fs::equivalent(path[0], a));  // missing and empty entries skipped
    CHECK(fs::equivalent(path[1], b));
    const auto m = names();
    CHECK(m.count("none") == 0);
    CHECK(m.count("fancy@running") == 0);
    fs::remove_all(a);
    fs::remove_all(b);
}

TEST_CASE("model names: an unknown name lists the folders and the known names", "[model_names]") {
    const fs::path a = fresh_dir("unknown");
    write(a / "mine.safetensors", "x");
    EnvGuard env("NGI_MODEL_PATH", a.string());
    const std::string msg = message_of_resolve("surroundd");
    CHECK_THAT(msg, Catch::Contains("model 'surroundd'"));
    CHECK_THAT(msg, Catch::Contains("not a known model name"));
    CHECK_THAT(msg, Catch::Contains(fs::weakly_canonical(a).string()));
    CHECK_THAT(msg, Catch::Contains("known names: "));
    CHECK_THAT(msg, Catch::Contains("mine"));
    CHECK_THAT(msg, Catch::Contains("surround"));
    CHECK_THAT(message_of_resolve(""), Catch::Contains("empty"));
    fs::remove_all(a);
}

TEST_CASE("model names: a broken zoo.json or a missing file is an error naming it", "[model_names]") {
    const fs::path a = fresh_dir("broken");
    EnvGuard env("NGI_MODEL_PATH", a.string());
    const std::string zoo = (fs::weakly_canonical(a) / "zoo.json").string();
    write(a / "zoo.json", "{\"format\": \"ngi-zoo\", \"rungs\": [");  // truncated
    std::string msg = message_of_resolve("surround");
    CHECK_THAT(msg, Catch::Contains(zoo) && Catch::Contains("not valid JSON"));
    write(a / "zoo.json", R"({"format": "something else", "rungs": []})");
    CHECK_THAT(message_of_resolve("surround"), Catch::Contains(zoo) && Catch::Contains("not a zoo manifest"));
    write(a / "zoo.json", R"({"format": "ngi-zoo", "rungs": [{"file": "x.safetensors"}]})");
    CHECK_THAT(message_of_resolve("surround"), Catch::Contains(zoo) && Catch::Contains("without a \"name\""));
    write(a / "zoo.json", R"({"format": "ngi-zoo", "rungs": [{"name": "gone", "file": "gone.safetensors"}]})");
    msg = message_of_resolve("gone");
    CHECK_THAT(msg, Catch::Contains("model 'gone'") && Catch::Contains("gone.safetensors") &&
                        Catch::Contains("does not exist"));
    fs::remove_all(a);
}
