// Dataset rendering: config parsing, the split, deterministic per-frame parameters, resumable frame folders.
#include "ngi/dataset.hpp"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>

#include "base/file_util.hpp"
#include "base/json_strict.hpp"
#include "render/rand.hpp"
#include "ngi/error.hpp"
#include "ngi/image_io.hpp"

namespace ngi {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

std::uint32_t fnv1a(const std::string& s) {
    std::uint32_t h = 2166136261u;
    for (unsigned char c : s) h = (h ^ c) * 16777619u;
    return h;
}

std::uint32_t mix32(std::uint32_t x) {  // a 32-bit finalizer (lowbias32): spreads nearby inputs apart
    x ^= x >> 16; x *= 0x7feb352dU; x ^= x >> 15; x *= 0x846ca68bU; x ^= x >> 16;
    return x;
}

// A scene given by a file (.vox or a mesh) rather than a family spec: resolved against the config's folder, and
// its dataset folder named after the file.
bool is_vox(const std::string& spec) {
    std::string e = fs::path(spec).extension().string();
    for (auto& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
    return e == ".vox" || is_mesh_path(spec);
}

struct ConfigReader {
    std::string file;
    [[noreturn]] void fail(const std::string& what) const { throw InputError("dataset config " + file + ": " + what); }

    void keys(const json& j, const std::set<std::string>& allowed, const std::string& where) const {
        if (!j.is_object()) fail(where + " must be an object");
        for (auto it = j.begin(); it != j.end(); ++it)
            if (!allowed.count(it.key())) fail("unknown key '" + it.key() + "' in " + where);
    }
    int integer(const json& j, const char* key, int fallback, int lo, int hi) const {
        if (!j.contains(key)) return fallback;
        const json& v = j[key];
        if (!v.is_number_integer() || v.get<long long>() < lo || v.get<long long>() > hi)
            fail(std::string("'") + key + "' must be an integer in " + std::to_string(lo) + ".." + std::to_string(hi));
        return v.get<int>();
    }
    float hours(const json& v, const std::string& where) const {
        if (!v.is_number() || v.get<double>() < 0.0 || v.get<double>() > 48.0)
            fail("'time' in " + where + " must be hours in 0..48 (or a [start, end] pair)");
        return v.get<float>();
    }

    std::vector<DatasetScene> split(const json& arr, const std::string& name, const fs::path& base) const {
        if (!arr.is_array()) fail("'" + name + "' must be an array of scene entries");
        std::vector<DatasetScene> out;
        for (std::size_t i = 0; i < arr.size(); ++i) {
            const json& e = arr[i];
            const std::string where = name + "[" + std::to_string(i) + "]";
            keys(e, {"scene", "family", "seeds", "vox", "time", "frames"}, where);
            DatasetScene proto;
            if (e.contains("time")) {
                const json& t = e["time"];
                if (t.is_array()) {
                    if (t.size() != 2) fail("'time' in " + where + " must be hours or [start, end]");
                    proto.time_start = hours(t[0], where);
                    proto.time_end = hours(t[1], where);
                    // Frames interpolate from start to end; hours run to 48 so that a night crosses midnight
                    // forward ([22, 26]), and a range that runs backwards is a typo, not a path.
                    if (proto.time_end < proto.time_start)
                        fail("'time' in " + where + " is [" + t[0].dump() + ", " + t[1].dump() +
                             "]: the end is before the start (hours run to 48: [22, 26] crosses midnight)");
                } else {
                    proto.time_start = proto.time_end = hours(t, where);
                }
            }  // else: negative, the scene's own default time
            proto.frames = integer(e, "frames", 0, 1, kMaxPathFrames);  // one camera path per entry
            const int kinds = int(e.contains("scene")) + int(e.contains("family")) + int(e.contains("vox"));
            if (kinds != 1) fail(where + " needs exactly one of 'scene', 'family' (+ 'seeds') or 'vox'");
            auto add = [&](std::string spec) {
                if (is_vox(spec)) spec = fs::absolute(base / spec).lexically_normal().string();
                DatasetScene d = proto;
                d.spec = std::move(spec);
                out.push_back(d);
            };
            if (e.contains("scene")) {
                if (!e["scene"].is_string()) fail("'scene' in " + where + " must be a string");
                add(e["scene"].get<std::string>());
            } else if (e.contains("vox")) {
                if (!e["vox"].is_string()) fail("'vox' in " + where + " must be a string");
                add(e["vox"].get<std::string>());
            } else {
                if (!e["family"].is_string()) fail("'family' in " + where + " must be a string");
                const std::string fam = e["family"].get<std::string>();
                if (!e.contains("seeds")) fail(where + " has a 'family' but no 'seeds'");
                const json& s = e["seeds"];
                std::vector<std::uint32_t> seeds;
                if (s.is_array()) {
                    for (const auto& v : s) {
                        if (!v.is_number_unsigned()) fail("'seeds' in " + where + " must hold unsigned integers");
                        seeds.push_back(v.get<std::uint32_t>());
                    }
                } else if (s.is_object()) {
                    keys(s, {"first", "count"}, where + ".seeds");
                    const int first = integer(s, "first", 0, 0, 2000000000), count = integer(s, "count", 1, 1, 100000);
                    for (int k = 0; k < count; ++k) seeds.push_back(std::uint32_t(first + k));
                } else {
                    fail("'seeds' in " + where + " must be a list or {\"first\": F, \"count\": C}");
                }
                for (auto sd : seeds) add(fam + ":seed=" + std::to_string(sd));
            }
        }
        return out;
    }

    glm::vec3 vec3(const json& j, const char* key, const std::string& where) const {
        if (!j.contains(key)) fail(where + " needs '" + key + "'");
        const json& v = j[key];
        if (!v.is_array() || v.size() != 3) fail(std::string("'") + key + "' in " + where + " must be [x, y, z]");
        glm::vec3 out;
        for (int k = 0; k < 3; ++k) {
            if (!v[k].is_number() || !std::isfinite(v[k].get<double>()) || std::abs(v[k].get<double>()) > 1.0e6)
                fail(std::string("'") + key + "' in " + where + " must hold finite numbers within +-1e6");
            out[k] = v[k].get<float>();
        }
        return out;
    }
    float metres(const json& j, const char* key, const std::string& where) const {
        if (!j.contains(key)) fail(where + " needs '" + key + "'");
        const json& v = j[key];
        if (!v.is_number() || !(v.get<double>() >= 1.0e-3 && v.get<double>() <= 1.0e4))
            fail(std::string("'") + key + "' in " + where + " must be metres in 0.001..10000");
        return v.get<float>();
    }

    DatasetAreaLight area_light(const json& j) const {
        const std::string where = "'area_light'";
        keys(j, {"centre_min", "centre_max", "size_min", "size_max", "facing", "radiance"}, where);
        DatasetAreaLight a;
        a.centre_min = vec3(j, "centre_min", where);
        a.centre_max = vec3(j, "centre_max", where);
        for (int k = 0; k < 3; ++k)
            if (a.centre_min[k] > a.centre_max[k]) fail("'centre_min' in " + where + " exceeds 'centre_max'");
        a.size_min = metres(j, "size_min", where);
        a.size_max = metres(j, "size_max", where);
        if (a.size_min > a.size_max) fail("'size_min' in " + where + " exceeds 'size_max'");
        a.radiance = vec3(j, "radiance", where);
        if (a.radiance.r < 0 || a.radiance.g < 0 || a.radiance.b < 0)
            fail("'radiance' in " + where + " must not be negative");
        if (j.contains("facing")) {
            const json& f = j["facing"];
            static const std::set<std::string> kFacings = {"down", "up", "+x", "-x", "+z", "-z"};
            if (!f.is_string() || !kFacings.count(f.get<std::string>()))
                fail("'facing' in " + where + " must be one of \"down\", \"up\", \"+x\", \"-x\", \"+z\", \"-z\"");
            a.facing = f.get<std::string>();
        }
        return a;
    }
};

json vec(glm::vec3 v) { return json::array({v.x, v.y, v.z}); }

json to_json(const DatasetConfig& c) {
    auto scenes = [](const std::vector<DatasetScene>& v) {
        json a = json::array();
        for (const auto& s : v)
            a.push_back({{"scene", s.spec}, {"time", {s.time_start, s.time_end}}, {"frames", s.frames}});
        return a;
    };
    json j = {{"n", c.render.n}, {"feature_spp", c.render.feature_spp}, {"reference_spp", c.render.reference_spp},
              {"max_bounces", c.render.max_bounces}, {"rr_start", c.render.rr_start},
              {"frames_per_scene", c.frames_per_scene}, {"keyframe_interval", c.keyframe_interval},
              {"train", scenes(c.train)}, {"test", scenes(c.test)}};
    // Only when set, so that the dataset.json of a dataset rendered before this key existed still matches.
    if (c.test_reference_spp > 0) j["test_reference_spp"] = c.test_reference_spp;
    if (c.camera_path != CameraPathKind::Auto) j["camera_path"] = camera_path_kind_name(c.camera_path);  // likewise
    if (c.area_light) {  // likewise
        const DatasetAreaLight& a = *c.area_light;
        j["area_light"] = {{"centre_min", vec(a.centre_min)}, {"centre_max", vec(a.centre_max)},
                           {"size_min", a.size_min}, {"size_max", a.size_max}, {"facing", a.facing},
                           {"radiance", vec(a.radiance)}};
    }
    return j;
}

std::string frame_name(int f) {
    char b[16];
    std::snprintf(b, sizeof b, "%04d", f);
    return b;
}

}  // namespace

DatasetConfig DatasetConfig::load(const std::string& path) {
    return parse(detail::read_file(path, "dataset config"), path);
}

DatasetConfig DatasetConfig::parse(const std::string& text, const std::string& path) {
    ConfigReader r{path};
    json j;
    try {
        j = detail::parse_json_unique_keys(text, "dataset config " + path + ": ");
    } catch (const json::exception& e) {
        r.fail(std::string("not valid JSON: ") + e.what());
    }
    r.keys(j, {"n", "feature_spp", "reference_spp", "test_reference_spp", "max_bounces", "rr_start",
               "frames_per_scene", "keyframe_interval", "train", "test", "area_light", "camera_path", "comment"},
           "the top level");
    DatasetConfig c;
    c.render.n = r.integer(j, "n", c.render.n, 1, 8192);
    c.render.feature_spp = r.integer(j, "feature_spp", c.render.feature_spp, 1, 1 << 20);
    c.render.reference_spp = r.integer(j, "reference_spp", c.render.reference_spp, 1, 1 << 20);
    c.test_reference_spp = r.integer(j, "test_reference_spp", 0, 0, 1 << 20);
    c.render.max_bounces = r.integer(j, "max_bounces", c.render.max_bounces, 0, 1000);
    c.render.rr_start = r.integer(j, "rr_start", c.render.rr_start, 0, 1000);
    c.frames_per_scene = r.integer(j, "frames_per_scene", c.frames_per_scene, 1, kMaxPathFrames);
    c.keyframe_interval = r.integer(j, "keyframe_interval", c.keyframe_interval, 1, 100000);
    if (j.contains("area_light")) c.area_light = r.area_light(j["area_light"]);
    if (j.contains("camera_path")) {
        if (!j["camera_path"].is_string()) r.fail("'camera_path' must be \"auto\", \"fly\" or \"orbit\"");
        try {
            c.camera_path = parse_camera_path_kind(j["camera_path"].get<std::string>(), "'camera_path'");
        } catch (const InputError& e) {
            r.fail(e.what());
        }
    }
    if (!j.contains("train")) r.fail("no 'train' scenes");
    const fs::path base = fs::path(path).parent_path();
    c.train = r.split(j["train"], "train", base);
    if (j.contains("test")) c.test = r.split(j["test"], "test", base);

    // Canonical scene names: a scene may appear once, and never in both splits.
    std::set<std::string> seen;
    for (auto* split : {&c.train, &c.test})
        for (auto& s : *split) {
            s.spec = scene_spec_name(s.spec);
            const std::string& name = s.spec;
            if (!seen.insert(dataset_scene_folder(name)).second)
                r.fail("scene '" + name + "' appears more than once (train and test scenes must be disjoint)");
        }
    return c;
}

CameraPath dataset_camera_path(const VoxelScene& scene, int frames, int interval, CameraPathKind kind) {
    return make_camera_path(scene, kind, frames, fnv1a(scene.name), interval);
}

std::uint32_t dataset_frame_seed(const std::string& scene_name, int frame) {
    return mix32(fnv1a(scene_name) ^ mix32(std::uint32_t(frame) + 0x9e3779b9u));
}

float dataset_frame_time(const DatasetScene& s, int frame, int frames) {
    if (frames <= 1) return s.time_start;
    return s.time_start + (s.time_end - s.time_start) * float(frame) / float(frames - 1);
}

AreaLight dataset_frame_area_light(const DatasetAreaLight& c, std::uint32_t frame_seed) {
    // Its own stream of the frame's seed: the light does not move when anything else drawn per frame changes.
    detail::Rand r(frame_seed, 0x41524541u);  // "AREA"
    AreaLight l;
    for (int k = 0; k < 3; ++k) l.centre[k] = r.range(c.centre_min[k], c.centre_max[k]);
    const float a = 0.5f * r.range(c.size_min, c.size_max), b = 0.5f * r.range(c.size_min, c.size_max);
    // Half edges along two axes, ordered so that cross(half_u, half_v) points toward `facing`.
    const glm::vec3 x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
    if (c.facing == "down") { l.half_u = a * x; l.half_v = b * z; }
    else if (c.facing == "up") { l.half_u = a * z; l.half_v = b * x; }
    else if (c.facing == "+x") { l.half_u = a * y; l.half_v = b * z; }
    else if (c.facing == "-x") { l.half_u = a * z; l.half_v = b * y; }
    else if (c.facing == "+z") { l.half_u = a * x; l.half_v = b * y; }
    else if (c.facing == "-z") { l.half_u = a * y; l.half_v = b * x; }
    else throw InputError("dataset: area light facing '" + c.facing + "' is not down, up, +x, -x, +z or -z");
    l.radiance = c.radiance;
    return l;
}

std::string dataset_scene_folder(const std::string& name) {
    if (is_vox(name)) return fs::path(name).stem().string();
    std::string out;
    for (char c : name) {
        if (c == ':' || c == ',') out += '_';
        else if (c != '=') out += c;
    }
    return out;
}

namespace {

// Every scene of both splits is built (so a .vox file is found and parsed) and its camera path computed, before
// anything is written: a bad test scene must not surface only after hours of training frames.
void validate_scenes(const DatasetConfig& config) {
    const std::pair<const char*, const std::vector<DatasetScene>*> splits[] = {{"train", &config.train},
                                                                                {"test", &config.test}};
    for (const auto& [split_name, scenes] : splits)
        for (std::size_t i = 0; i < scenes->size(); ++i) {
            const DatasetScene& entry = (*scenes)[i];
            const int frames = entry.frames > 0 ? entry.frames : config.frames_per_scene;
            try {
                const VoxelScene scene = make_scene(entry.spec);
                dataset_camera_path(scene, frames, config.keyframe_interval, config.camera_path);
            } catch (const Error& e) {
                throw InputError(std::string("dataset: ") + split_name + " scene " + std::to_string(i) + " (" +
                                 entry.spec + "): " + e.what() + "; nothing was written");
            }
        }
}

// Frame folders (<scene folder>/<frame>/camera.json) finished under a scene folder.
int finished_frames(const fs::path& scene_dir) {
    std::error_code ec;
    int n = 0;
    for (fs::directory_iterator it(scene_dir, ec), end; !ec && it != end; it.increment(ec))
        n += it->is_directory(ec) && fs::exists(it->path() / "camera.json", ec);
    return n;
}

// out/dataset.json records the config the frames under `out` were rendered with. A different config is accepted
// when it does not contradict any finished frame: the global settings (n, spp, bounces, frames per scene, ...)
// may change only while no frame exists at all, and a scene entry only while its folder holds no frame (e.g. a
// test .vox path corrected after an earlier run stopped on it). Anything else is refused, naming what to delete.
void check_stored_config(const fs::path& out, const json& stored, const json& wanted) {
    const std::string cfg_path = (out / "dataset.json").string();
    if (!stored.is_object() || !stored.contains("train") || !stored.contains("test"))
        throw InputError("dataset: " + cfg_path + " is not a dataset.json written by ngi; use another output folder");
    int total = 0;
    std::string first_finished;
    for (const char* split : {"train", "test"}) {
        std::error_code ec;
        for (fs::directory_iterator it(out / split, ec), end; !ec && it != end; it.increment(ec)) {
            if (!it->is_directory(ec)) continue;
            const int n = finished_frames(it->path());
            if (n == 0) continue;
            total += n;
            if (first_finished.empty()) first_finished = it->path().string();
            // The entry of this folder in each config (dataset_scene_folder is unique within a config).
            auto entry_of = [&](const json& cfg) -> std::string {
                for (const auto& e : cfg[split])
                    if (e.contains("scene") && e["scene"].is_string() &&
                        dataset_scene_folder(e["scene"].get<std::string>()) == it->path().filename().string())
                        return e.dump();
                return "";
            };
            const std::string had = entry_of(stored), want = entry_of(wanted);
            if (had != want)
                throw InputError("dataset: " + it->path().string() + " holds " + std::to_string(n) +
                                 " frames rendered for " + (had.empty() ? std::string("a scene of no config") : had) +
                                 ", but the config now " +
                                 (want.empty() ? std::string("does not list it") : "asks for " + want) +
                                 "; delete that folder to re-render it with the new config, or use another output "
                                 "folder");
        }
    }
    json stored_globals = stored, wanted_globals = wanted;
    for (json* g : {&stored_globals, &wanted_globals}) {
        g->erase("train");
        g->erase("test");
    }
    if (total > 0 && stored_globals != wanted_globals)
        throw InputError("dataset: " + cfg_path + " was written for a different config (" + stored_globals.dump() +
                         ", now " + wanted_globals.dump() + ") and " + std::to_string(total) +
                         " frames of it are rendered (e.g. " + first_finished +
                         "); frames of two settings must not mix: use another output folder, or delete " +
                         out.string() +
                         " to start over");
}

}  // namespace

void prepare_dataset(const DatasetConfig& config, const std::string& out_dir) {
    const fs::path out(out_dir);
    validate_scenes(config);
    const json wanted = to_json(config);
    const std::string cfg = wanted.dump(2) + "\n";
    const fs::path cfg_path = out / "dataset.json";
    std::error_code ec;
    if (fs::exists(out, ec) && !fs::is_directory(out, ec))
        throw InputError("dataset: " + out_dir + " exists and is not a directory");
    if (fs::exists(cfg_path, ec)) {
        const std::string text = detail::read_file(cfg_path.string());
        if (text != cfg) {
            json stored;
            try {
                stored = json::parse(text);
            } catch (const json::exception& e) {
                throw InputError("dataset: " + cfg_path.string() + " is not valid JSON (" + e.what() +
                                 "); use another output folder");
            }
            check_stored_config(out, stored, wanted);
            detail::write_file_atomic(cfg_path.string(), cfg);  // nothing finished contradicts the new config
        }
    } else {
        // A mistyped --out (the home folder, another dataset's split) must not fill up with train/ and test/.
        if (fs::exists(out, ec) && !fs::is_empty(out, ec))
            throw InputError("dataset: " + out_dir + " exists, is not empty and holds no dataset.json; use a new or "
                             "empty output folder (or the folder of an earlier run of this dataset)");
        fs::create_directories(out, ec);
        if (ec) throw InputError("dataset: cannot create " + out_dir + ": " + ec.message());
        detail::write_file_atomic(cfg_path.string(), cfg);
    }
}

namespace {

int frames_of(const DatasetConfig& config, const DatasetScene& s) {
    return s.frames > 0 ? s.frames : config.frames_per_scene;
}

// Every scene of the dataset with its split and the ordinal of its first frame (the shard numbering).
struct SceneSlot {
    const char* split;
    const DatasetScene* entry;
    long long first;
};
std::vector<SceneSlot> scene_slots(const DatasetConfig& config) {
    std::vector<SceneSlot> slots;
    long long ordinal = 0;
    const std::pair<const char*, const std::vector<DatasetScene>*> splits[] = {{"train", &config.train},
                                                                                {"test", &config.test}};
    for (const auto& [split_name, scenes] : splits)
        for (const DatasetScene& entry : *scenes) {
            slots.push_back({split_name, &entry, ordinal});
            ordinal += frames_of(config, entry);
        }
    return slots;
}

}  // namespace

std::pair<int, int> count_dataset_frames(const DatasetConfig& config, const std::string& out_dir) {
    int done = 0, total = 0;
    for (const SceneSlot& slot : scene_slots(config)) {
        const fs::path dir = fs::path(out_dir) / slot.split / dataset_scene_folder(slot.entry->spec);
        const int frames = frames_of(config, *slot.entry);
        total += frames;
        std::error_code ec;
        for (int f = 0; f < frames; ++f) done += fs::exists(dir / frame_name(f) / "camera.json", ec);
    }
    return {done, total};
}

void render_dataset(const Device& device, const DatasetConfig& config, const std::string& out_dir,
                    const std::function<void(const DatasetProgress&)>& progress, const DatasetShard& shard) {
    if (shard.count < 1 || shard.index < 0 || shard.index >= shard.count)
        throw InputError("dataset: shard " + std::to_string(shard.index) + " of " + std::to_string(shard.count) +
                         " does not exist");
    const fs::path out(out_dir);
    // One process: prepare here. Several: the coordinator prepared the folder; check that it matches this
    // process's config (a shard never writes dataset.json, so shards cannot race on it).
    if (shard.count == 1) prepare_dataset(config, out_dir);
    else {
        validate_scenes(config);
        const fs::path cfg_path = out / "dataset.json";
        std::error_code ec;
        if (!fs::exists(cfg_path, ec) || detail::read_file(cfg_path.string()) != to_json(config).dump(2) + "\n")
            throw InputError("dataset: " + cfg_path.string() + " is missing or holds another config than this "
                             "shard's: every process of a distributed run must be given the same config");
    }

    const std::vector<SceneSlot> slots = scene_slots(config);
    DatasetProgress p;
    for (const SceneSlot& slot : slots)
        for (int f = 0; f < frames_of(config, *slot.entry); ++f) p.frames_total += shard.owns(slot.first + f);

    std::error_code ec;
    for (const SceneSlot& slot : slots) {
        const DatasetScene& entry = *slot.entry;
        const int frames = frames_of(config, entry);
        auto mine = [&](int f) { return shard.owns(slot.first + f); };
        int my_frames = 0;
        for (int f = 0; f < frames; ++f) my_frames += mine(f);
        if (my_frames == 0) continue;
        const fs::path dir = out / slot.split / dataset_scene_folder(entry.spec);
        fs::create_directories(dir, ec);  // (a folder without frames: a rerun may still change this entry)
        if (ec) throw InputError("dataset: cannot create " + dir.string() + ": " + ec.message());
        p.scene = dir.filename().string();
        // Leftovers of a killed run: write_frame's temporary folders (<frame>.tmp-*) never become frames; remove
        // those of this shard's frames (another shard's may be in progress right now).
        for (const auto& e : fs::directory_iterator(dir, ec)) {
            const std::string name = e.path().filename().string();
            const auto tmp = name.find(".tmp-");
            if (tmp == std::string::npos) continue;
            const std::string stem = name.substr(0, tmp);
            const bool frame_tmp = !stem.empty() && stem.size() <= 9 &&
                                   stem.find_first_not_of("0123456789") == std::string::npos;
            if (frame_tmp ? !mine(std::stoi(stem)) : shard.count > 1) continue;  // another shard's, maybe in progress
            fs::remove_all(e.path(), ec);
        }
        auto done = [&](int f) { return fs::exists(dir / frame_name(f) / "camera.json"); };
        int missing = 0;
        for (int f = 0; f < frames; ++f) missing += mine(f) && !done(f);
        if (missing == 0 && fs::exists(dir / "scene.json")) {
            p.frames_done += my_frames;
            p.frames_skipped += my_frames;
            if (progress) progress(p);
            continue;
        }

        const VoxelScene scene = make_scene(entry.spec);
        const CameraPath path = dataset_camera_path(scene, frames, config.keyframe_interval, config.camera_path);
        DatasetScene times = entry;
        if (times.time_start < 0) times.time_start = times.time_end = scene.default_time;
        json info = {{"spec", scene.name}, {"split", slot.split}, {"frames", frames},
                     {"size", {scene.size.x, scene.size.y, scene.size.z}}, {"sun_azimuth", scene.sun_azimuth},
                     {"keyframe_interval", path.interval}};
        json keys = json::array(), per_frame = json::array();
        for (const auto& k : path.keys)
            keys.push_back({{"position", vec(k.position)},
                            {"orientation_wxyz", {k.orientation.w, k.orientation.x, k.orientation.y, k.orientation.z}}});
        for (int f = 0; f < frames; ++f) {
            const CameraPose pose = path.at(float(f));
            per_frame.push_back({{"frame", f}, {"time", dataset_frame_time(times, f, frames)},
                                 {"seed", dataset_frame_seed(scene.name, f)}, {"position", vec(pose.position)},
                                 {"look", vec(pose.look)}, {"up", vec(pose.up)}});
        }
        info["keyframes"] = keys;
        info["frame_info"] = per_frame;
        detail::write_file_atomic((dir / "scene.json").string(), info.dump(1) + "\n");

        Renderer renderer(device, scene);
        for (int f = 0; f < frames; ++f) {
            if (!mine(f)) continue;
            if (done(f)) {
                ++p.frames_done;
                ++p.frames_skipped;
                if (progress) progress(p);
                continue;
            }
            const auto t0 = std::chrono::steady_clock::now();
            RenderSettings rs = config.render;
            rs.seed = dataset_frame_seed(scene.name, f);
            if (slot.split == std::string("test") && config.test_reference_spp > 0)
                rs.reference_spp = config.test_reference_spp;
            rs.reference = true;
            rs.reference_face = Face::Front;
            RenderStats stats;
            Lighting lighting = lighting_at(dataset_frame_time(times, f, frames), scene.sun_azimuth);
            if (config.area_light) lighting.area_light = dataset_frame_area_light(*config.area_light, rs.seed);
            const Frame frame = renderer.render(path.at(float(f)), lighting, rs, &stats);
            write_frame((dir / frame_name(f)).string(), frame);
            ++p.frames_done;
            ++p.frames_rendered;
            p.rendered_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            p.last_rel_stderr = stats.reference_rel_stderr;
            if (progress) progress(p);
        }
    }
}

}  // namespace ngi
