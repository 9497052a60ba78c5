// Dataset configs and the resumable, deterministic dataset writer.
#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include "models/family.hpp"
#include "ngi/dataset.hpp"
#include "ngi/error.hpp"
#include "ngi/image_io.hpp"
#include "ngi/render.hpp"
#include "io_test_support.hpp"
#include "test_support.hpp"

using namespace ngi;
namespace fs = std::filesystem;
using Catch::Matchers::Contains;

namespace {

// Per process: test runs of several build trees on one machine (or the same tests under PoCL and oclgrind at
// once) must not share an output folder ("dataset.json was written for a different config").
fs::path work_dir() { return fs::temp_directory_path() / ("ngi_render_dataset-" + std::to_string(getpid())); }

std::string write_config(const std::string& name, const std::string& text) {
    const fs::path dir = work_dir();
    fs::create_directories(dir);
    const fs::path p = dir / name;
    std::ofstream(p) << text;
    return p.string();
}

std::string frame_name_for_test(int f) {
    char b[16];
    std::snprintf(b, sizeof b, "%04d", f);
    return b;
}

std::string config_error(const std::string& text) {
    try {
        DatasetConfig::load(write_config("bad.json", text));
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST_CASE("dataset config: entries, times, and disjoint splits", "[render]") {
    const std::string p = write_config("ok.json", R"({
        "n": 32, "reference_spp": 8, "frames_per_scene": 10,
        "train": [{"family": "room", "seeds": [1, 2], "time": [12, 20]},
                  {"family": "cave", "seeds": {"first": 5, "count": 3}},
                  {"scene": "street", "frames": 4, "time": 9}],
        "test": [{"scene": "room:seed=3"}, {"vox": "model.vox"}]})");
    const DatasetConfig c = DatasetConfig::load(p);
    CHECK(c.render.n == 32);
    CHECK(c.render.reference_spp == 8);
    CHECK(c.frames_per_scene == 10);
    REQUIRE(c.train.size() == 6);
    CHECK(c.train[0].spec == "room:seed=1");
    CHECK(c.train[1].time_end == 20.0f);
    CHECK(c.train[4].spec == "cave:seed=7");
    CHECK(c.train[5].spec == "street:seed=0");
    CHECK(c.train[5].frames == 4);
    REQUIRE(c.test.size() == 2);
    CHECK(c.test[1].spec == fs::absolute(fs::path(p).parent_path() / "model.vox").lexically_normal().string());
    CHECK(c.train[2].time_start < 0.0f);  // no "time": the scene's default
    CHECK(dataset_frame_time(c.train[0], 0, 10) == 12.0f);
    CHECK(dataset_frame_time(c.train[0], 9, 10) == 20.0f);
    CHECK(dataset_scene_folder("room:seed=12") == "room_seed12");
    CHECK(dataset_scene_folder("/a/b/house.vox") == "house");

    CHECK_THAT(config_error(R"({"train": [{"family": "room", "seeds": [1, 2]}], "test": [{"scene": "room:seed=2"}]})"),
               Catch::Contains("room:seed=2") && Catch::Contains("disjoint") && Catch::Contains("bad.json"));
    CHECK_THAT(config_error(R"({"train": [{"scene": "cave"}], "test": [{"scene": "cave:seed=0"}]})"),
               Catch::Contains("cave:seed=0"));
    CHECK_THAT(config_error(R"({"train": [], "spp": 3})"), Catch::Contains("unknown key 'spp'"));
    CHECK_THAT(config_error(R"({"train": [{"family": "lava", "seeds": [1]}]})"), Catch::Contains("unknown family"));
    CHECK_THAT(config_error(R"({"train": [{"scene": "room", "time": [1]}]})"), Catch::Contains("'time'"));
    CHECK_THAT(config_error(R"({"n": 0, "train": []})"), Catch::Contains("'n'"));
    CHECK_THAT(config_error("{\"train\": [,]}"), Catch::Contains("not valid JSON"));
}

TEST_CASE("dataset configs refuse duplicate keys and backwards time ranges", "[render][dataset]") {
    const std::string train = R"("train": [{"scene": "room:seed=1"}])";
    REQUIRE_NOTHROW(ngi::DatasetConfig::parse("{\"n\": 8, " + train + "}", "/tmp/c.json"));
    // nlohmann keeps the last of two equal keys silently: {"n": 64, "n": 8} rendered at 8.
    CHECK_THROWS_WITH(ngi::DatasetConfig::parse("{\"n\": 64, \"n\": 8, " + train + "}", "/tmp/c.json"),
                      Contains("/tmp/c.json") && Contains("duplicate key 'n'"));
    CHECK_THROWS_WITH(ngi::DatasetConfig::parse(R"({"train": [{"scene": "room:seed=1", "frames": 2, "frames": 3}]})",
                                                "/tmp/c.json"),
                      Contains("duplicate key 'frames'"));
    // Equal keys in different objects are fine.
    CHECK_NOTHROW(ngi::DatasetConfig::parse(
        R"({"train": [{"scene": "room:seed=1", "frames": 2}], "test": [{"scene": "room:seed=2", "frames": 2}]})",
        "/tmp/c.json"));
    // A time range runs forward; hours go to 48 so that a night crosses midnight forward.
    CHECK_THROWS_WITH(ngi::DatasetConfig::parse(R"({"train": [{"scene": "room:seed=1", "time": [20, 10]}]})",
                                                "/tmp/c.json"),
                      Contains("train[0]") && Contains("end is before the start"));
    CHECK_NOTHROW(ngi::DatasetConfig::parse(R"({"train": [{"scene": "room:seed=1", "time": [22, 26]}]})", "/tmp/c.json"));
    CHECK_NOTHROW(ngi::DatasetConfig::parse(R"({"train": [{"scene": "room:seed=1", "time": [12, 12]}]})", "/tmp/c.json"));
    // Model metadata too.
    REQUIRE_NOTHROW(ngi::detail::parse_model_config(R"({"family": "mlp", "input_nc": 3, "layers": [{"out": 1}]})",
                                                    "m.safetensors"));
    CHECK_THROWS_WITH(ngi::detail::parse_model_config(
                          R"({"family": "mlp", "input_nc": 3, "input_nc": 4, "layers": [{"out": 1}]})", "dup.safetensors"),
                      Contains("dup.safetensors") && Contains("duplicate key 'input_nc'"));
}

TEST_CASE("dataset: frame folders, resumable and deterministic", "[render][oclgrind-small]") {
    const fs::path out = work_dir() / "out";
    fs::remove_all(out);
    const std::string cfg_path = write_config("tiny.json", R"({
        "n": 8, "feature_spp": 1, "reference_spp": 2, "frames_per_scene": 3, "keyframe_interval": 2,
        "train": [{"family": "bleed", "seeds": [1], "time": [12, 20]}],
        "test": [{"scene": "backlit:seed=2", "frames": 2}]})");
    const DatasetConfig cfg = DatasetConfig::load(cfg_path);
    std::vector<DatasetProgress> seen;
    render_dataset(test::device(), cfg, out.string(), [&](const DatasetProgress& p) { seen.push_back(p); });
    REQUIRE(seen.size() == 5);
    CHECK(seen.back().frames_total == 5);
    CHECK(seen.back().frames_rendered == 5);
    CHECK(seen.back().frames_skipped == 0);
    const fs::path f0 = out / "train" / "bleed_seed1" / "0000";
    const Frame a = read_frame(f0.string());
    CHECK(a.n == 8);
    CHECK(a.reference);
    CHECK(fs::exists(out / "test" / "backlit_seed2" / "0001" / "camera.json"));
    CHECK_FALSE(fs::exists(out / "test" / "backlit_seed2" / "0002"));
    CHECK(fs::exists(out / "train" / "bleed_seed1" / "scene.json"));
    CHECK(fs::exists(out / "dataset.json"));

    // A rerun skips everything; a lost frame and a killed run's temporary folder are redone / cleaned up, and the
    // redone frame is bit-identical to the first one.
    seen.clear();
    render_dataset(test::device(), cfg, out.string(), [&](const DatasetProgress& p) { seen.push_back(p); });
    CHECK(seen.back().frames_skipped == 5);
    CHECK(seen.back().frames_rendered == 0);
    fs::remove_all(f0);
    fs::create_directories(out / "train" / "bleed_seed1" / "0001.tmp-999-0");
    seen.clear();
    render_dataset(test::device(), cfg, out.string(), [&](const DatasetProgress& p) { seen.push_back(p); });
    CHECK(seen.back().frames_rendered == 1);
    CHECK_FALSE(fs::exists(out / "train" / "bleed_seed1" / "0001.tmp-999-0"));
    const Frame b = read_frame(f0.string());
    CHECK(b.reference->data == a.reference->data);
    for (int f = 0; f < kFeatureCount; ++f)
        for (int face = 0; face < kFaceCount; ++face) CHECK(b.faces[f][face].data == a.faces[f][face].data);

    // Another config must not write into this dataset: other settings would mix with the rendered frames.
    DatasetConfig other = cfg;
    other.render.reference_spp = 3;
    CHECK_THROWS_WITH(render_dataset(test::device(), other, out.string()),
                      Catch::Contains("different config") && Catch::Contains("another output folder"));
    // Nor a changed entry of a scene with rendered frames; the message names the folder to delete.
    other = cfg;
    other.test[0].frames = 1;
    CHECK_THROWS_WITH(render_dataset(test::device(), other, out.string()),
                      Catch::Contains((out / "test" / "backlit_seed2").string()) &&
                          Catch::Contains("delete that folder"));
    const std::string stored = test::slurp((out / "dataset.json").string());

    // A scene whose folder holds no frame may change (the corrected config after a run that stopped before it):
    // accepted, and dataset.json now records the new config.
    fs::remove_all(out / "test" / "backlit_seed2");
    seen.clear();
    render_dataset(test::device(), other, out.string(), [&](const DatasetProgress& p) { seen.push_back(p); });
    CHECK(seen.back().frames_rendered == 1);
    CHECK(seen.back().frames_skipped == 3);
    CHECK(fs::exists(out / "test" / "backlit_seed2" / "0000" / "camera.json"));
    CHECK_FALSE(fs::exists(out / "test" / "backlit_seed2" / "0001"));
    CHECK(test::slurp((out / "dataset.json").string()) != stored);
}

TEST_CASE("dataset: shards render disjoint frames whose union is the single-process dataset", "[render]") {
    const fs::path single = work_dir() / "shard_single", sharded = work_dir() / "shard_3";
    fs::remove_all(single);
    fs::remove_all(sharded);
    const DatasetConfig cfg = DatasetConfig::load(write_config("shards.json", R"({
        "n": 8, "feature_spp": 1, "reference_spp": 2, "frames_per_scene": 3, "keyframe_interval": 2,
        "train": [{"family": "bleed", "seeds": [1]}, {"scene": "room:seed=2", "frames": 2}],
        "test": [{"scene": "backlit:seed=2", "frames": 2}]})"));
    render_dataset(test::device(), cfg, single.string());
    // A shard needs the prepared folder (what rank 0 does first), and refuses one of another config.
    CHECK_THROWS_WITH(render_dataset(test::device(), cfg, sharded.string(), {}, DatasetShard{1, 3}),
                      Catch::Contains("same config"));
    CHECK_THROWS_AS(render_dataset(test::device(), cfg, sharded.string(), {}, DatasetShard{3, 3}), InputError);
    prepare_dataset(cfg, sharded.string());
    CHECK(count_dataset_frames(cfg, sharded.string()) == std::pair<int, int>(0, 7));
    int rendered = 0;
    for (int k : {2, 0, 1}) {  // any order: the shards are independent
        std::vector<DatasetProgress> seen;
        render_dataset(test::device(), cfg, sharded.string(), [&](const DatasetProgress& p) { seen.push_back(p); },
                       DatasetShard{k, 3});
        REQUIRE_FALSE(seen.empty());
        CHECK(seen.back().frames_total == (k == 0 ? 3 : 2));  // frames k, k + 3, k + 6 of 7
        rendered += seen.back().frames_rendered;
        if (k == 2) {  // only its own frames: ordinals 2 (bleed 0002) and 5 (backlit 0000)
            CHECK(fs::exists(sharded / "train" / "bleed_seed1" / "0002" / "camera.json"));
            CHECK(fs::exists(sharded / "test" / "backlit_seed2" / "0000" / "camera.json"));
            CHECK_FALSE(fs::exists(sharded / "train" / "bleed_seed1" / "0000"));
            CHECK_FALSE(fs::exists(sharded / "train" / "room_seed2"));  // no frame of its: not even the folder
            CHECK(count_dataset_frames(cfg, sharded.string()).first == 2);
        }
    }
    CHECK(rendered == 7);
    // Byte for byte the same files as one process.
    std::vector<std::string> a, b;
    for (const auto& e : fs::recursive_directory_iterator(single)) a.push_back(fs::relative(e.path(), single).string());
    for (const auto& e : fs::recursive_directory_iterator(sharded)) b.push_back(fs::relative(e.path(), sharded).string());
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    REQUIRE(a == b);
    for (const auto& rel : a)
        if (fs::is_regular_file(single / rel)) {
            INFO(rel);
            CHECK(test::slurp((single / rel).string()) == test::slurp((sharded / rel).string()));
        }
}

TEST_CASE("dataset: the whole config is validated before anything is written", "[render]") {
    const fs::path out = work_dir() / "out_invalid";
    fs::remove_all(out);
    // The training scene is fine; the test split names a .vox file that does not exist.
    const std::string bad = write_config("missing_vox.json", R"({
        "n": 8, "feature_spp": 1, "reference_spp": 2, "frames_per_scene": 1,
        "train": [{"scene": "bleed:seed=1"}], "test": [{"vox": "no_such_scene.vox"}]})");
    CHECK_THROWS_WITH(render_dataset(test::device(), DatasetConfig::load(bad), out.string()),
                      Catch::Contains("no_such_scene.vox") && Catch::Contains("test scene 0") &&
                          Catch::Contains("nothing was written"));
    CHECK_FALSE(fs::exists(out));

    // The corrected config then renders normally into the same folder.
    const std::string good = write_config("fixed_vox.json", R"({
        "n": 8, "feature_spp": 1, "reference_spp": 2, "frames_per_scene": 1,
        "train": [{"scene": "bleed:seed=1"}], "test": [{"scene": "backlit:seed=2"}]})");
    render_dataset(test::device(), DatasetConfig::load(good), out.string());
    CHECK(fs::exists(out / "train" / "bleed_seed1" / "0000" / "camera.json"));
    CHECK(fs::exists(out / "test" / "backlit_seed2" / "0000" / "camera.json"));
    fs::remove_all(out);

    // A non-empty folder that is not a dataset is not written into.
    fs::create_directories(out);
    test::spit((out / "notes.txt").string(), "mine");
    CHECK_THROWS_WITH(render_dataset(test::device(), DatasetConfig::load(good), out.string()),
                      Catch::Contains("holds no dataset.json"));
    CHECK_FALSE(fs::exists(out / "train"));
    fs::remove_all(out);
}

TEST_CASE("dataset: test_reference_spp gives the test split's references their own sample count", "[render]") {
    const fs::path out = work_dir() / "out_test_spp";
    fs::remove_all(out);
    const DatasetConfig cfg = DatasetConfig::load(write_config("test_spp.json", R"({
        "n": 8, "feature_spp": 1, "reference_spp": 1, "test_reference_spp": 6, "frames_per_scene": 1,
        "train": [{"scene": "bleed:seed=1"}], "test": [{"scene": "room:seed=3"}]})"));
    CHECK(cfg.test_reference_spp == 6);
    render_dataset(test::device(), cfg, out.string());
    // Each split's reference equals a render of the same frame (camera, light, seed) at that split's spp.
    auto check_split = [&](const std::string& spec, const char* split, int spp) {
        const VoxelScene scene = make_scene(spec);
        RenderSettings rs = cfg.render;
        rs.reference_spp = spp;
        rs.seed = dataset_frame_seed(scene.name, 0);
        rs.reference = true;
        rs.reference_face = Face::Front;
        Renderer renderer(test::device(), scene);
        const Frame want = renderer.render(dataset_camera_path(scene, 1, cfg.keyframe_interval).at(0.0f),
                                           lighting_at(scene.default_time, scene.sun_azimuth), rs);
        const Frame got = read_frame((out / split / dataset_scene_folder(scene.name) / "0000").string());
        CHECK(got.reference->data == want.reference->data);
    };
    check_split("room:seed=3", "test", 6);
    check_split("bleed:seed=1", "train", 1);
    CHECK(test::slurp((out / "dataset.json").string()).find("\"test_reference_spp\"") != std::string::npos);
    CHECK_THAT(config_error(R"({"train": [], "test_reference_spp": -1})"), Catch::Contains("test_reference_spp"));
    fs::remove_all(out);
}

TEST_CASE("dataset: an area_light config draws one light per frame from the frame's seed, recorded in the frame",
          "[render][area]") {
    const fs::path out = work_dir() / "out_area";
    fs::remove_all(out);
    const DatasetConfig cfg = DatasetConfig::load(write_config("area.json", R"({
        "n": 8, "feature_spp": 1, "reference_spp": 2, "frames_per_scene": 2,
        "area_light": {"centre_min": [3, 4, 3], "centre_max": [6, 4.5, 6], "size_min": 0.5, "size_max": 2,
                       "radiance": [4, 3, 2]},
        "train": [{"scene": "bleed:seed=1"}]})"));
    REQUIRE(cfg.area_light.has_value());
    CHECK(cfg.area_light->facing == "down");
    render_dataset(test::device(), cfg, out.string());
    const VoxelScene scene = make_scene("bleed:seed=1");
    const CameraPath path = dataset_camera_path(scene, 2, cfg.keyframe_interval);
    std::vector<AreaLight> lights;
    for (int f = 0; f < 2; ++f) {
        const std::uint32_t seed = dataset_frame_seed(scene.name, f);
        const AreaLight want = dataset_frame_area_light(*cfg.area_light, seed);
        // Inside the configured ranges, facing down.
        for (int k = 0; k < 3; ++k) {
            CHECK(want.centre[k] >= cfg.area_light->centre_min[k]);
            CHECK(want.centre[k] <= cfg.area_light->centre_max[k]);
        }
        CHECK(2.0f * glm::length(want.half_u) >= 0.5f);
        CHECK(2.0f * glm::length(want.half_v) <= 2.0f);
        CHECK(want.normal().y == Approx(-1.0f));
        CHECK(want.radiance == glm::vec3(4, 3, 2));
        CHECK(dataset_frame_area_light(*cfg.area_light, seed) == want);  // deterministic
        lights.push_back(want);
        const Frame got = read_frame((out / "train" / dataset_scene_folder(scene.name) / frame_name_for_test(f)).string());
        REQUIRE(got.area_light.has_value());
        CHECK(*got.area_light == want);
        REQUIRE(got.position.has_value());
        CHECK(*got.position == path.at(float(f)).position);
        // The reference equals a render of that frame with that light.
        RenderSettings rs = cfg.render;
        rs.seed = seed;
        Lighting lighting = lighting_at(scene.default_time, scene.sun_azimuth);
        lighting.area_light = want;
        Renderer renderer(test::device(), scene);
        CHECK(renderer.render_reference(path.at(float(f)), lighting, rs).data == got.reference->data);
    }
    CHECK_FALSE(lights[0] == lights[1]);  // a new light per frame
    CHECK(test::slurp((out / "dataset.json").string()).find("\"area_light\"") != std::string::npos);
    // Adding an area light to a dataset with frames is a different config.
    DatasetConfig other = cfg;
    other.area_light->radiance = glm::vec3(1.0f);
    CHECK_THROWS_WITH(render_dataset(test::device(), other, out.string()), Catch::Contains("different config"));

    for (int facing = 0; facing < 6; ++facing) {  // every facing's normal points where it says
        const char* names[] = {"down", "up", "+x", "-x", "+z", "-z"};
        const glm::vec3 normals[] = {{0, -1, 0}, {0, 1, 0}, {1, 0, 0}, {-1, 0, 0}, {0, 0, 1}, {0, 0, -1}};
        DatasetAreaLight a = *cfg.area_light;
        a.facing = names[facing];
        const AreaLight l = dataset_frame_area_light(a, 7);
        CHECK_NOTHROW(check_area_light(l, "test"));
        CHECK(glm::length(l.normal() - normals[facing]) < 1e-6f);
    }
    CHECK_THAT(config_error(R"({"train": [], "area_light": {"centre_min": [0, 0, 0], "centre_max": [1, 1, 1],
                                "size_min": 1, "size_max": 1, "radiance": [1, -1, 1]}})"),
               Catch::Contains("'radiance' in 'area_light'"));
    CHECK_THAT(config_error(R"({"train": [], "area_light": {"centre_min": [0, 2, 0], "centre_max": [1, 1, 1],
                                "size_min": 1, "size_max": 1, "radiance": [1, 1, 1]}})"),
               Catch::Contains("'centre_min' in 'area_light'"));
    CHECK_THAT(config_error(R"({"train": [], "area_light": {"centre_min": [0, 0, 0], "centre_max": [1, 1, 1],
                                "size_min": 1, "size_max": 1, "radiance": [1, 1, 1], "facing": "sideways"}})"),
               Catch::Contains("'facing' in 'area_light'"));
    CHECK_THAT(config_error(R"({"train": [], "area_light": {"centre_min": [0, 0, 0], "centre_max": [1, 1, 1],
                                "size_min": 0, "size_max": 1, "radiance": [1, 1, 1]}})"),
               Catch::Contains("'size_min' in 'area_light'"));
    fs::remove_all(out);
}
