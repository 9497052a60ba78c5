// Writes the seed corpora of the fuzz targets: small valid files made with ngi's own writers (and OpenEXR for the
// compressions and tilings ngi does not write itself), plus a few near-misses. Run by tools/fuzz.sh --corpus:
//   ngi_make_corpus <source dir>/fuzz/corpus
// Deterministic: the same build writes the same bytes.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfOutputFile.h>
#include <ImfTiledOutputFile.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <stdexcept>
#include <fstream>
#include <iostream>
#include <set>
#include <nlohmann/json.hpp>

#include "frame_folder_format.hpp"
#include "base/file_util.hpp"
#include "models/safetensors.hpp"
#include "ngi/image_io.hpp"
#include "ngi/tensor.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

fs::path root;

// Each target folder this program writes is emptied the first time it is written to, so a rerun drops seeds it
// no longer makes; the folders of targets with their own seed scripts (vox, mesh: make_*_seeds.py and the
// fuzzers' reproducers) are never touched.
void put(const std::string& target, const std::string& name, const std::string& bytes) {
    static std::set<std::string> emptied;
    if (emptied.insert(target).second) fs::remove_all(root / target);
    fs::create_directories(root / target);
    std::ofstream(root / target / name, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
}

// Writes with an ngi writer into a scratch file and returns the bytes.
template <class F>
std::string via_file(const std::string& ext, F&& write) {
    const fs::path p = fs::temp_directory_path() / ("ngi-make-corpus" + ext);
    write(p.string());
    std::string b = ngi::detail::read_file(p.string());
    fs::remove(p);
    return b;
}

ngi::Image ramp(int w, int h, int c) {
    ngi::Image img(w, h, c);
    for (std::size_t i = 0; i < img.data.size(); ++i) img.data[i] = float(i % 7) / 6.0f;
    return img;
}

class MemoryOStream : public Imf::OStream {
public:
    MemoryOStream() : Imf::OStream("memory") {}
    void write(const char c[], int n) override {
        if (pos_ + std::size_t(n) > bytes.size()) bytes.resize(pos_ + std::size_t(n));
        std::memcpy(bytes.data() + pos_, c, std::size_t(n));
        pos_ += std::size_t(n);
    }
    std::uint64_t tellp() override { return pos_; }
    void seekp(std::uint64_t pos) override { pos_ = pos; }
    std::string bytes;

private:
    std::size_t pos_ = 0;
};

// A 4x4 RGB half image with the given compression; tiled (2x2 tiles, mipmapped) when asked.
std::string exr_with(Imf::Compression compression, bool tiled, bool data_window_offset) {
    std::vector<Imath::half> px(4 * 4 * 3);
    for (std::size_t i = 0; i < px.size(); ++i) px[i] = Imath::half(float(i % 5) * 0.25f);
    Imath::Box2i disp({0, 0}, {3, 3}), dw = data_window_offset ? Imath::Box2i({1, 1}, {4, 4}) : disp;
    Imf::Header h(disp, dw);
    h.compression() = compression;
    Imf::FrameBuffer fb;
    const char* names[3] = {"R", "G", "B"};
    for (int c = 0; c < 3; ++c) {
        h.channels().insert(names[c], Imf::Channel(Imf::HALF));
        char* base = reinterpret_cast<char*>(px.data() + c * 16) -
                     (dw.min.x + dw.min.y * 4) * std::ptrdiff_t(sizeof(Imath::half));
        fb.insert(names[c], Imf::Slice(Imf::HALF, base, sizeof(Imath::half), 4 * sizeof(Imath::half)));
    }
    MemoryOStream out;
    if (tiled) {
        h.setTileDescription(Imf::TileDescription(2, 2, Imf::ONE_LEVEL));
        Imf::TiledOutputFile f(out, h);
        f.setFrameBuffer(fb);
        f.writeTiles(0, f.numXTiles() - 1, 0, f.numYTiles() - 1);
    } else {
        Imf::OutputFile f(out, h);
        f.setFrameBuffer(fb);
        f.writePixels(4);
    }
    return out.bytes;
}

std::string npy_raw(const std::string& descr, const std::string& shape, const std::string& data, int major = 1) {
    std::string header = "{'descr': '" + descr + "', 'fortran_order': False, 'shape': " + shape + ", }";
    header += std::string((64 - (header.size() + 13) % 64) % 64, ' ') + "\n";
    std::string b("\x93NUMPY", 6);
    b += char(major);
    b += '\0';
    const std::size_t n = header.size();
    b += char(n & 0xff);
    b += char(n >> 8);
    if (major >= 2) b += std::string(2, '\0');
    return b + header + data;
}

// A safetensors file of the named tensors (constant values) and config, as ngi.model_file (Python) writes it.
std::string safetensors(const std::vector<std::pair<std::string, std::vector<int>>>& tensors, const json& config,
                        bool half) {
    json header = json::object();
    std::string data;
    for (const auto& [name, shape] : tensors) {
        std::size_t n = 1;
        for (int d : shape) n *= std::size_t(d);
        const std::size_t begin = data.size();
        for (std::size_t i = 0; i < n; ++i) {
            if (half) data += std::string("\x66\x2e", 2);  // 0.0999 in IEEE half, little-endian
            else { const float v = 0.1f; data.append(reinterpret_cast<const char*>(&v), 4); }
        }
        header[name] = {{"dtype", half ? "F16" : "F32"}, {"shape", shape}, {"data_offsets", {begin, data.size()}}};
    }
    header["__metadata__"] = {{"ngi", config.dump()}};
    std::string h = header.dump();
    while (h.size() % 8) h += ' ';
    std::string b(8, '\0');
    for (int i = 0; i < 8; ++i) b[i] = char((std::uint64_t(h.size()) >> (8 * i)) & 0xff);
    return b + h + data;
}

std::vector<std::pair<std::string, std::vector<int>>> tiny_pix2pix() {  // num_downs 5, ngf 1, 1 -> 1 channel
    std::vector<std::pair<std::string, std::vector<int>>> e;
    auto bn = [&](const std::string& p, int c) {
        for (const char* f : {".weight", ".bias", ".running_mean", ".running_var"}) e.push_back({p + f, {c}});
    };
    e.push_back({"model.model.0.weight", {1, 1, 4, 4}});
    e.push_back({"model.model.3.weight", {2, 1, 4, 4}});
    e.push_back({"model.model.3.bias", {1}});
    const int inner[5] = {1, 2, 4, 8, 8};
    std::string seq = "model.model.1.model";
    for (int i = 1; i <= 3; ++i) {
        e.push_back({seq + ".1.weight", {inner[i], inner[i - 1], 4, 4}});
        bn(seq + ".2", inner[i]);
        e.push_back({seq + ".5.weight", {2 * inner[i], inner[i - 1], 4, 4}});
        bn(seq + ".6", inner[i - 1]);
        seq += ".3.model";
    }
    e.push_back({seq + ".1.weight", {8, 8, 4, 4}});
    e.push_back({seq + ".3.weight", {8, 8, 4, 4}});
    bn(seq + ".4", 8);
    return e;
}

json full_config() {
    return {{"format_version", 1}, {"family", "pix2pix_unet"}, {"input_nc", 1}, {"output_nc", 1}, {"ngf", 1},
            {"num_downs", 5}, {"norm", "batch"}, {"bn_mode", "per_image"}, {"bn_eps", 1e-5}, {"dropout", "off"},
            {"dropout_p", 0.5}, {"dropout_seed", 0}, {"leaky_slope", 0.2}, {"input_layout", {"albedo.r"}},
            {"input_range", {-1, 1}}, {"output_range", {-1, 1}}, {"source", "fuzz seed"}};
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::cerr << "usage: ngi_make_corpus <fuzz/corpus folder>\n";
        return 2;
    }
    root = argv[1];

    // npy
    put("npy", "f4_c_h_w.npy", via_file(".npy", [](const std::string& p) {
            ngi::Tensor t({3, 2, 2});
            for (std::size_t i = 0; i < t.data.size(); ++i) t.data[i] = float(i);
            ngi::write_npy(p, t);
        }));
    put("npy", "f4_1d.npy", via_file(".npy", [](const std::string& p) { ngi::write_npy(p, ngi::Tensor({4})); }));
    put("npy", "f4_scalar.npy", via_file(".npy", [](const std::string& p) { ngi::write_npy(p, ngi::Tensor(std::vector<int>{})); }));
    put("npy", "f8_v2.npy", npy_raw("<f8", "(2, 1)", std::string(16, '\0'), 2));
    put("npy", "f2.npy", npy_raw("<f2", "(1, 3)", std::string("\x00\x3c\x00\xc0\x00\x7c", 6)));
    put("npy", "empty_dim.npy", npy_raw("<f4", "(1, 0, 3)", ""));

    // exr
    put("exr", "rgb_half.exr", via_file(".exr", [](const std::string& p) { ngi::write_exr(p, ramp(4, 4, 3)); }));
    put("exr", "y_float.exr", via_file(".exr", [](const std::string& p) {
            ngi::write_exr(p, ramp(3, 2, 1), ngi::ExrPixelType::Float);
        }));
    put("exr", "rgba.exr", via_file(".exr", [](const std::string& p) { ngi::write_exr(p, ramp(2, 2, 4)); }));
    put("exr", "c12.exr", via_file(".exr", [](const std::string& p) { ngi::write_exr(p, ramp(2, 2, 12)); }));
    put("exr", "layers.exr", via_file(".exr", [](const std::string& p) {
            ngi::write_exr(p, ramp(2, 2, 4), ngi::ExrPixelType::Half, {"diffuse.R", "diffuse.G", "A", "Z"});
        }));
    const std::pair<const char*, Imf::Compression> comps[] = {
        {"none", Imf::NO_COMPRESSION}, {"rle", Imf::RLE_COMPRESSION},   {"zips", Imf::ZIPS_COMPRESSION},
        {"piz", Imf::PIZ_COMPRESSION}, {"pxr24", Imf::PXR24_COMPRESSION}, {"b44", Imf::B44_COMPRESSION},
        {"b44a", Imf::B44A_COMPRESSION}, {"dwaa", Imf::DWAA_COMPRESSION}, {"dwab", Imf::DWAB_COMPRESSION}};
    for (const auto& [name, c] : comps) put("exr", std::string(name) + ".exr", exr_with(c, false, false));
    put("exr", "tiled_zip.exr", exr_with(Imf::ZIP_COMPRESSION, true, false));
    put("exr", "tiled_rle.exr", exr_with(Imf::RLE_COMPRESSION, true, false));
    put("exr", "data_window_offset.exr", exr_with(Imf::NO_COMPRESSION, false, true));

    // png
    for (int c = 1; c <= 4; ++c)
        put("png", "c" + std::to_string(c) + ".png",
            via_file(".png", [c](const std::string& p) { ngi::write_png(p, ramp(3, 2, c)); }));
    put("png", "srgb_5x3.png",
        via_file(".png", [](const std::string& p) { ngi::write_png(p, ramp(5, 3, 3), ngi::PngEncoding::Srgb); }));

    // camera.json
    put("camera_json", "default.json", "{\"look\": [0, 0, -1], \"up\": [0, 1, 0]}\n");
    put("camera_json", "tilted.json", "{\"look\": [0.3, -0.2, -0.9], \"up\": [0, 1, 0.1], \"fov\": 90}\n");
    put("camera_json", "parallel.json", "{\"look\": [0, 1, 0], \"up\": [0, 2, 0]}\n");

    // dataset config
    put("dataset_config", "small.json",
        R"({"n": 32, "feature_spp": 4, "reference_spp": 16, "max_bounces": 4, "rr_start": 2, "frames_per_scene": 3,
 "keyframe_interval": 2, "comment": "seed",
 "train": [{"family": "room", "seeds": [1, 2]}, {"scene": "cave:seed=3", "time": [10, 20], "frames": 2},
           {"family": "street", "seeds": {"first": 5, "count": 2}, "time": 12.5}],
 "test": [{"vox": "scenes/castle.vox"}, {"scene": "bleed"}]})");
    put("dataset_config", "minimal.json", R"({"train": [{"scene": "room:seed=1"}]})");
    put("dataset_config", "duplicate.json", R"({"train": [{"scene": "room:seed=1"}], "test": [{"family": "room", "seeds": [1]}]})");

    // plan (ngi lightmap --plan)
    put("plan_file", "rung.json", R"({"format": "ngi-plan", "version": 1, "rung": "s", "model": "/proc/self/exe", "n": 64, "bn_mode": "running"})");
    put("plan_file", "switch.json", R"({"format": "ngi-plan", "version": 1, "rung": "s", "model": "/proc/self/exe", "n": 64,
 "switch": {"below_outside_light_share": 0.6, "rung": "v", "model": "/proc/self/exe", "n": 64, "bn_mode": "per_image"}})");
    put("plan_file", "direct.json", R"({"format": "ngi-plan", "version": 1, "rung": "direct_only", "model": null, "n": 32})");
    put("plan_file", "guard.json", R"({"format": "ngi-plan", "version": 1, "rung": "s", "model": "/proc/self/exe", "n": 64,
 "guard": {"max_indirect_share": 0.4}})");

    // safetensors
    const auto tiny = tiny_pix2pix();
    put("safetensors", "tiny_f32.safetensors", safetensors(tiny, full_config(), false));
    put("safetensors", "tiny_f16.safetensors", safetensors(tiny, full_config(), true));
    json minimal = {{"family", "pix2pix_unet"}, {"input_nc", 1}, {"output_nc", 1}, {"ngf", 1}, {"num_downs", 5}};
    put("safetensors", "tiny_minimal_config.safetensors", safetensors(tiny, minimal, false));
    json di = full_config();
    di["family"] = "deepillumination";
    di["num_downs"] = 8;
    put("safetensors", "deepillumination_config_only.safetensors", safetensors({{"conv1.weight", {1, 1, 4, 4}}}, di, false));

    // frame folder: edits of the base frame (fuzz/frame_folder_format.hpp)
    using ngi::fuzz::record;
    const auto& names = ngi::fuzz::frame_file_names();
    auto index = [&](const std::string& n) { return std::size_t(std::find(names.begin(), names.end(), n) - names.begin()); };
    put("frame_folder", "base", "");
    put("frame_folder", "camera", record(index("camera.json"), "{\"look\": [1, 0, 0], \"up\": [0, 1, 0]}"));
    const std::string face_exr = via_file(".exr", [](const std::string& p) { ngi::write_exr(p, ramp(2, 2, 3)); });
    const std::string face_png = via_file(".png", [](const std::string& p) { ngi::write_png(p, ramp(2, 2, 4)); });
    std::string emission;
    for (const char* face : {"front", "back", "left", "right", "up", "down"})
        emission += record(index(std::string(face) + "_emission.exr"), face_exr);
    put("frame_folder", "emission", emission);
    put("frame_folder", "albedo_png", record(index("front_albedo.exr"), "") + record(index("front_albedo.png"), face_png));
    put("frame_folder", "reference", record(index("reference.exr"), via_file(".exr", [](const std::string& p) {
                                                ngi::write_exr(p, ramp(3, 2, 3), ngi::ExrPixelType::Float);
                                            })));
    put("frame_folder", "missing_depth", record(index("left_depth.exr"), ""));
    // Extreme values (fuzz/frame_folder_format.hpp extreme_record: a, b index extreme_values(); layout bits 0-1
    // size (0 = 2x2), bit 2 half, bit 3 alpha, bits 4-6 pattern).
    const auto& ev = ngi::fuzz::extreme_values();
    auto value = [&](float v) {  // index of v in the table (NaN matched as NaN)
        for (std::size_t i = 0; i < ev.size(); ++i)
            if (ev[i] == v || (std::isnan(v) && std::isnan(ev[i]))) return std::uint8_t(i);
        throw std::logic_error("make_corpus: value not in extreme_values()");
    };
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    using ngi::fuzz::extreme_record;
    put("frame_folder", "extreme_nan_direct", extreme_record(index("front_direct.exr"), value(nan), value(1.0f), 0x10));
    put("frame_folder", "extreme_inf_albedo", extreme_record(index("back_albedo.exr"), value(inf), value(-inf), 0x10));
    put("frame_folder", "extreme_flt_max_depth", extreme_record(index("up_depth.exr"), value(FLT_MAX), value(1e5f), 0x20));
    put("frame_folder", "extreme_negative_depth", extreme_record(index("down_depth.exr"), value(0.5f), value(-1.0f), 0x20));
    put("frame_folder", "extreme_normal_half", extreme_record(index("left_normal.exr"), value(65504.0f), value(nan), 0x34));
    put("frame_folder", "extreme_reference_denormal",
        extreme_record(index("reference.exr"), value(std::numeric_limits<float>::denorm_min()), value(-FLT_MAX), 0x48));
    put("frame_folder", "extreme_zero", extreme_record(index("right_albedo.exr"), value(0.0f), value(0.0f), 0x00));
    std::string env;  // env on all six faces, constant 65520 written as half (rounds to Inf)
    for (const char* face : {"front", "back", "left", "right", "up", "down"})
        env += extreme_record(index(std::string(face) + "_env.exr"), value(65520.0f), value(0.0f), 0x04);
    put("frame_folder", "extreme_env_half_overflow", env);

    // model configs: byte 0 picks the family (fuzz_model_config.cpp), the rest is the config. The shipped models'
    // configs (their __metadata__["ngi"], two per family), each also with byte 6 (the "family" key as written).
    const fs::path models = root.parent_path().parent_path() / "models";
    const std::vector<std::string> families = {"pix2pix_unet", "deepillumination", "mlp", "neural_gi", "voxel_sh", "graph"};
    std::map<std::string, int> per_family;
    std::vector<fs::path> model_files;
    for (const auto& e : fs::recursive_directory_iterator(models))
        if (e.path().extension() == ".safetensors") model_files.push_back(e.path());
    std::sort(model_files.begin(), model_files.end());
    for (const fs::path& f : model_files) {
        const std::string cfg = ngi::detail::read_safetensors(f.string()).metadata.at("ngi");
        const std::string family = json::parse(cfg).at("family").get<std::string>();
        if (per_family[family]++ >= 2) continue;
        // A family the harness does not pick by byte 0 (ssgi) gets 6, "as written", like the second seed.
        const char pick = char(std::find(families.begin(), families.end(), family) - families.begin());
        put("model_config", f.stem().string(), std::string(1, pick) + cfg);
        put("model_config", f.stem().string() + "_as_written", std::string(1, char(6)) + cfg);
    }
    put("model_config", "deepillumination", std::string(1, char(1)) + di.dump());  // the safetensors seed's config
    // No graph model is shipped: a hand-written one with every op (docs/MODEL_FORMAT.md "graph").
    const json graph = {
        {"format_version", 1}, {"family", "graph"}, {"input_nc", 3}, {"output_nc", 3},
        {"graph", {{"layout", "nchw"}, {"input", "x"}, {"output", "y"}, {"nodes", json::array({
            {{"name", "clean"}, {"op", "nan_to_num"}, {"inputs", {"x"}}, {"output", "t0"}},
            {{"name", "enc"}, {"op", "frequency_encode"}, {"inputs", {"t0"}}, {"output", "t1"},
             {"encoding", {{"bands", 2}, {"include_input", true}}}},
            {{"name", "conv"}, {"op", "conv2d"}, {"inputs", {"t1"}}, {"output", "t2"}, {"in", 15}, {"out", 4},
             {"kernel", {4, 4}}, {"stride", 2}, {"pad", 1}, {"weight", "conv.w"}, {"activation", "leaky_relu"},
             {"slope", 0.2}},
            {{"name", "up"}, {"op", "conv_transpose2d"}, {"inputs", {"t2"}}, {"output", "t3"}, {"in", 4}, {"out", 3},
             {"kernel", {4, 4}}, {"stride", 2}, {"pad", 1}, {"weight", "up.w"}, {"bias", "up.b"},
             {"input_activation", "relu"}},
            {{"name", "bn"}, {"op", "affine"}, {"inputs", {"t3"}}, {"output", "t4"}, {"scale", "bn.s"}, {"shift", "bn.t"}},
            {{"name", "sum"}, {"op", "add"}, {"inputs", {"t4", "t0"}}, {"output", "t5"}},
            {{"name", "prod"}, {"op", "mul"}, {"inputs", {"t5", "t0"}}, {"output", "t6"}},
            {{"name", "cat"}, {"op", "concat"}, {"inputs", {"t6", "t0"}}, {"output", "t7"}},
            {{"name", "act"}, {"op", "activation"}, {"inputs", {"t7"}}, {"output", "t8"}, {"activation", "tanh"}},
            {{"name", "mix"}, {"op", "conv2d"}, {"inputs", {"t8"}}, {"output", "y"}, {"in", 6}, {"out", 3},
             {"kernel", {1, 1}}, {"stride", 1}, {"pad", 0}, {"weight", "mix.w"}, {"activation", "sigmoid"}}})}}},
        {"input_range", {-1, 1}}, {"source", "fuzz seed"}};
    put("model_config", "graph_every_op", std::string(1, char(5)) + graph.dump());
    // "up" above carries an input_activation, as files the converter fused did; since issue 49 ngi.convert writes the
    // network unfused and the loader fuses (models/graph_fuse.hpp): a batch norm's affine and a ReLU after a
    // convolution, a leaky ReLU read by two convolutions, a tanh at the output.
    auto seed_conv = [](const char* name, const char* in, const char* out, int cin, int cout, int k) {
        return json{{"name", name}, {"op", "conv2d"}, {"inputs", {in}}, {"output", out}, {"in", cin}, {"out", cout},
                    {"kernel", {k, k}}, {"stride", 1}, {"pad", k / 2}, {"weight", std::string(name) + ".w"}};
    };
    json c1 = seed_conv("c1", "x", "t1", 3, 4, 3);
    c1["bias"] = "c1.b";
    const json graph_unfused = {
        {"format_version", 1}, {"family", "graph"}, {"input_nc", 3}, {"output_nc", 3},
        {"graph", {{"layout", "nchw"}, {"input", "x"}, {"output", "y"}, {"nodes", json::array({
            c1,
            {{"name", "bn"}, {"op", "affine"}, {"inputs", {"t1"}}, {"output", "t2"}, {"scale", "bn.s"}, {"shift", "bn.t"}},
            {{"name", "r"}, {"op", "activation"}, {"inputs", {"t2"}}, {"output", "t3"}, {"activation", "relu"}},
            {{"name", "lk"}, {"op", "activation"}, {"inputs", {"x"}}, {"output", "t4"}, {"activation", "leaky_relu"},
             {"slope", 0.2}},
            seed_conv("c2", "t4", "t5", 3, 2, 1), seed_conv("c3", "t4", "t6", 3, 2, 1),
            {{"name", "cat"}, {"op", "concat"}, {"inputs", {"t3", "t5", "t6"}}, {"output", "t7"}},
            seed_conv("c4", "t7", "t8", 8, 3, 1),
            {{"name", "th"}, {"op", "activation"}, {"inputs", {"t8"}}, {"output", "y"}, {"activation", "tanh"}}})}}},
        {"input_range", {-1, 1}}, {"source", "fuzz seed"}};
    put("model_config", "graph_unfused", std::string(1, char(5)) + graph_unfused.dump());
    json graph_nc = {{"family", "graph"}, {"input_nc", 4},
                     {"graph", {{"layout", "nc"}, {"input", "in"}, {"output", "out"}, {"nodes", json::array({
                         {{"name", "d0"}, {"op", "dense"}, {"inputs", {"in"}}, {"output", "h"}, {"in", 4}, {"out", 8},
                          {"weight", "d0.w"}, {"bias", "d0.b"}, {"activation", "relu"}},
                         {{"name", "d1"}, {"op", "dense"}, {"inputs", {"h"}}, {"output", "out"}, {"in", 8}, {"out", 2},
                          {"weight", "d1.w"}, {"activation", "exp"}}})}}}};
    put("model_config", "graph_nc", std::string(1, char(5)) + graph_nc.dump());
    // No pixel_cnn model is shipped either: a hand-written one, reached as written (byte 6).
    const json pixel_cnn = {
        {"format_version", 1}, {"family", "pixel_cnn"}, {"input_nc", 5}, {"output_nc", 2},
        {"layers", json::array({{{"out", 7}, {"kernel", 3}, {"activation", "leaky_relu"}, {"slope", 0.15}},
                                {{"out", 9}, {"kernel", 5}, {"activation", "sigmoid"}},
                                {{"out", 2}, {"kernel", 1}, {"activation", "none"}}})},
        {"input_range", {-1, 1}}, {"source", "fuzz seed"}};
    put("model_config", "pixel_cnn_as_written", std::string(1, char(6)) + pixel_cnn.dump());
    std::cout << "wrote the seed corpora under " << root << "\n";
    return 0;
}
