// Rendering a training/test dataset of frame folders from a JSON config: scene families and seeds (or .vox
// files), frames per scene along automatic camera paths, time of day per frame, face size and sample counts, a
// train/test split with disjoint scenes. Deterministic (same config, same files) and resumable (finished frames
// are never rendered twice; a killed run loses at most the frames in flight). Layout and format: docs/RENDERER.md.
#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ngi/camera_path.hpp"
#include "ngi/device.hpp"
#include "ngi/render.hpp"

namespace ngi {

struct DatasetScene {
    std::string spec;                       // make_scene() spec: "room:seed=3" or a .vox path
    float time_start = -1.0f, time_end = -1.0f;  // hours at the first / last frame (linear in between);
                                                 // negative: the scene's default_time throughout
    int frames = 0;                         // frames of this scene (0 = the config's frames_per_scene)
};

// An optional rectangular area light drawn anew for every frame from the frame's seed (dataset_frame_area_light):
// centre uniform in the box [centre_min, centre_max] (world metres), each edge uniform in [size_min, size_max]
// metres, axis aligned, emitting toward `facing`, radiance `radiance`. The light is not geometry (it may float in
// the air); a centre inside a block is the config's business (the blocks hide it).
struct DatasetAreaLight {
    glm::vec3 centre_min{0.0f}, centre_max{0.0f};
    float size_min = 1.0f, size_max = 1.0f;
    std::string facing = "down";  // "down" (a ceiling panel, normal -y), "up", "+x", "-x", "+z", "-z"
    glm::vec3 radiance{0.0f};
    bool operator==(const DatasetAreaLight&) const = default;
};

struct DatasetConfig {
    RenderSettings render;                  // n, feature_spp, reference_spp, max_bounces, rr_start (seed: per frame)
    int test_reference_spp = 0;             // reference spp of the test split (0: reference_spp): converged
                                            // references for evaluation, cheaper ones for training
    int frames_per_scene = 100;
    int keyframe_interval = 25;
    std::vector<DatasetScene> train, test;
    std::optional<DatasetAreaLight> area_light;  // absent: no area light (every dataset before this key)
    CameraPathKind camera_path = CameraPathKind::Auto;  // "camera_path": auto (orbit for .vox, fly otherwise),
                                                        // fly or orbit; stored in dataset.json only when not auto

    // JSON (docs/RENDERER.md): {"n", "feature_spp", "reference_spp", "test_reference_spp", "max_bounces",
    // "frames_per_scene",
    // "keyframe_interval", "train": [entry...], "test": [entry...]}, entry = {"scene": "room:seed=3"} or
    // {"family": "room", "seeds": [1, 2] | {"first": 1, "count": 4}} or {"vox": "file.vox"}, plus optional
    // "time": hours | [start, end] and "frames"; optional "area_light": {"centre_min": [x, y, z], "centre_max":
    // [x, y, z], "size_min": m, "size_max": m, "radiance": [r, g, b], "facing": "down"} (facing optional); optional
    // "camera_path": "auto" | "fly" | "orbit" (make_camera_path). Relative .vox paths are relative to the config file (and are
    // stored as absolute paths, so a resumed run from another directory sees the same config).
    // Throws InputError naming the file for bad JSON, unknown keys, bad values, and scenes in both splits.
    static DatasetConfig load(const std::string& path);
    // The same from the file's text; `path` names the file in errors and is the base of relative .vox paths.
    static DatasetConfig parse(const std::string& text, const std::string& path);
};

// The per-scene camera path and per-frame seed the dataset uses, so that `ngi render --frame K` reproduces
// frame K of a dataset scene exactly. `kind` as the config's "camera_path" (Auto: an orbit for .vox scenes, the
// fly-through for procedural ones).
CameraPath dataset_camera_path(const VoxelScene& scene, int frames, int interval,
                               CameraPathKind kind = CameraPathKind::Auto);
std::uint32_t dataset_frame_seed(const std::string& scene_name, int frame);
float dataset_frame_time(const DatasetScene& scene, int frame, int frames);
// The area light of the frame with seed `frame_seed` (dataset_frame_seed): deterministic in both arguments.
AreaLight dataset_frame_area_light(const DatasetAreaLight& config, std::uint32_t frame_seed);

// A file-system-safe folder name for a scene: "room_seed3", or the .vox file's stem.
std::string dataset_scene_folder(const std::string& scene_name);

struct DatasetProgress {
    int frames_total = 0;
    int frames_done = 0;       // rendered in this run + skipped
    int frames_skipped = 0;    // already on disk
    int frames_rendered = 0;
    double rendered_seconds = 0;   // wall time spent rendering in this run
    std::string scene;             // the scene being worked on
    double last_rel_stderr = 0;    // of the last rendered reference
};

// Renders every frame missing under out_dir: <out_dir>/<split>/<scene folder>/<frame:04d>/ frame folders, a
// scene.json per scene (spec, times and camera poses of every frame) and <out_dir>/dataset.json (the config).
// Before writing anything, every scene of both splits is built (.vox files found and parsed) and its camera path
// computed: a bad entry anywhere is an InputError naming it, and nothing is written.
// out_dir must be new, empty, or hold a dataset.json (else InputError: a mistyped path is not written into).
// out_dir/dataset.json records the config; a different config is accepted only if it contradicts no finished
// frame: the global settings may differ only while no frame exists, a scene entry only while its folder holds no
// frame (e.g. a corrected test entry after a run that stopped on it). Otherwise InputError naming what differs and
// what to delete (the scene folder, or the whole dataset) or to use another output folder.
//
// Several processes (MPI ranks, ngi-dataset-mpi) render one dataset together: prepare_dataset() once (rank 0),
// then render_dataset() in every process with its DatasetShard. Frames are numbered over the whole dataset (train
// scenes, then test scenes, in config order, frame 0 first) and frame k belongs to shard k % count, so the split is
// deterministic for any count and the union of the shards is exactly the single-process dataset, bit for bit
// (every frame's seed comes from its scene and index, never from who renders it). A shard writes only its own
// frames, removes only its own frames' leftover temporaries, and writes scene.json of the scenes it has frames in
// (every writer writes the same bytes, atomically).
struct DatasetShard {
    int index = 0, count = 1;  // this process's shard, of `count`
    bool owns(long long frame_ordinal) const { return frame_ordinal % count == index; }
};
// Validates the config and every scene, creates out_dir and writes (or checks) dataset.json: everything
// render_dataset does before it renders, so that shards started afterwards find a dataset folder that matches.
void prepare_dataset(const DatasetConfig& config, const std::string& out_dir);
// progress counts this shard's frames only (frames_total = the shard's share).
void render_dataset(const Device& device, const DatasetConfig& config, const std::string& out_dir,
                    const std::function<void(const DatasetProgress&)>& progress = {}, const DatasetShard& shard = {});
// Frames of the dataset already finished on disk (a camera.json in the frame folder), and all of them: what a
// coordinator reports while the shards run.
std::pair<int, int> count_dataset_frames(const DatasetConfig& config, const std::string& out_dir);

}  // namespace ngi
