// The frame folder (layout, sanitizing and pixel types are documented in ngi/image_io.hpp).
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>

#include "io/decode.hpp"
#include "base/file_util.hpp"
#include "ngi/error.hpp"
#include "ngi/image_io.hpp"
#include "ngi/output_folder.hpp"

namespace fs = std::filesystem;

namespace ngi {
namespace {

bool png_allowed(Feature f) { return f != Feature::Normal && f != Feature::Depth; }
bool optional_feature(Feature f) { return f == Feature::Emission || f == Feature::Env; }
bool is_empty(const Image& img) { return img.width == 0 && img.height == 0; }

std::string size_string(const Image& img) { return std::to_string(img.width) + "x" + std::to_string(img.height); }

// Keeps the first `want` channels when the only extra one is an alpha channel; anything else is an error.
Image fit_channels(Image img, int want, bool extra_is_alpha, const std::string& path) {
    if (img.channels == want) return img;
    if (want == 3 && img.channels == 4 && extra_is_alpha) {
        img.data.resize(img.plane() * 3);  // planar: dropping the last plane is a resize
        img.channels = 3;
        return img;
    }
    throw InputError("read " + path + ": has " + std::to_string(img.channels) + " channel(s), expected " +
                     std::to_string(want) + (want == 3 ? " (R, G, B; an extra alpha channel A is allowed)" : ""));
}

// The non-finite rules of docs/CONVENTIONS.md section 6 (preprocessing), applied at load time so that a frame read
// from disk and the same frame handed over in memory give the same network input. `kind` is the face feature;
// the reference follows the lighting rule (Feature::Direct). Negative depth is an error.
void sanitize(Image& img, Feature kind, const std::string& file, const std::string& path, FrameReadStats& stats) {
    constexpr float kMax = std::numeric_limits<float>::max();
    SanitizedFile s{file, 0, 0};
    auto count = [&](float v) { s.nan += std::isnan(v); s.inf += std::isinf(v); };
    if (kind == Feature::Depth) {
        const std::size_t negative = std::count_if(img.data.begin(), img.data.end(), [](float v) { return v < 0.0f; });
        if (negative)  // -Inf included; NaN compares false
            throw InputError("read " + path + ": " + std::to_string(negative) + " of " +
                             std::to_string(img.data.size()) + " pixels have a negative depth (depth is a distance)");
    }
    if (kind == Feature::Normal) {
        // A normal with a non-finite component has no direction: the whole vector becomes 0 (no surface), rather
        // than renormalizing what is left of it into a wrong direction.
        const std::size_t plane = img.plane();
        for (std::size_t p = 0; p < plane; ++p) {
            float* c[3] = {&img.data[p], &img.data[plane + p], &img.data[2 * plane + p]};
            if (std::isfinite(*c[0]) && std::isfinite(*c[1]) && std::isfinite(*c[2])) continue;
            for (float* v : c) { count(*v); *v = 0.0f; }
        }
    } else {
        for (float& v : img.data) {
            if (std::isfinite(v)) continue;
            count(v);
            if (kind == Feature::Depth) v = kMax;                                  // no hit: farther than anything
            else if (kind == Feature::Albedo) v = v > 0.0f ? 1.0f : 0.0f;          // NaN, -Inf -> 0; +Inf -> 1
            else v = v > 0.0f ? kMax : 0.0f;                                       // light: +Inf saturates
        }
    }
    if (s.nan || s.inf) stats.sanitized.push_back(std::move(s));
}

glm::vec3 json_vec3(const nlohmann::json& j, const char* key, const std::string& path) {
    if (!j.contains(key)) throw InputError("read " + path + ": missing \"" + key + "\"");
    const nlohmann::json& a = j[key];
    if (!a.is_array() || a.size() != 3 || !a[0].is_number() || !a[1].is_number() || !a[2].is_number())
        throw InputError("read " + path + ": \"" + key + "\" must be an array of 3 numbers");
    glm::vec3 v;
    for (int i = 0; i < 3; ++i) {
        // Checked as double first: converting a double beyond float's range (1e300) to float is undefined.
        const double d = a[i].get<double>();
        if (!std::isfinite(d) || std::abs(d) > std::numeric_limits<float>::max())
            throw InputError("read " + path + ": \"" + key + "\" must be finite (float range)");
        v[i] = float(d);
    }
    return v;
}

void read_camera(Frame& frame, const fs::path& file) {
    const std::string path = file.string();
    detail::decode_camera_json(detail::read_file(path), path, frame);
}

void check_image(const Image& img, int channels, int n, const std::string& name) {
    const bool shape_ok = img.channels == channels && (n < 0 || (img.width == n && img.height == n)) &&
                          img.width > 0 && img.height > 0 && img.data.size() == img.plane() * img.channels;
    if (!shape_ok)
        throw InputError(name + " is " + size_string(img) + "x" + std::to_string(img.channels) + " with " +
                         std::to_string(img.data.size()) + " values; expected " +
                         (n < 0 ? std::string("any size") : std::to_string(n) + "x" + std::to_string(n)) + "x" +
                         std::to_string(channels));
}

// An existing <dir> is replaced only if it is a frame folder (holds camera.json): a mistyped path never deletes
// unrelated files.
std::string frame_folder_replaceable(const std::string& existing) {
    std::error_code ec;
    return fs::exists(fs::path(existing) / "camera.json", ec) ? "" : "is not a frame folder (no camera.json)";
}

}  // namespace

void check_frame_folder_target(const std::string& dir) {
    OutputFolder(dir, "write frame", frame_folder_replaceable);  // checks only: the staging folder is made lazily
}

namespace {

nlohmann::json parse_camera_json(const std::string& text, const std::string& path) {
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(text);
    } catch (const std::exception& e) {
        throw InputError("read " + path + ": not valid JSON: " + e.what());
    }
    if (!j.is_object()) throw InputError("read " + path + ": expected a JSON object with \"look\" and \"up\"");
    return j;
}

void decode_look_up(const nlohmann::json& j, const std::string& path, glm::vec3& look, glm::vec3& up) {
    look = json_vec3(j, "look", path);
    up = json_vec3(j, "up", path);
    try {
        CameraCluster::from_look_up(look, up);
    } catch (const InputError& e) {
        throw InputError("read " + path + ": " + e.what());
    }
}

}  // namespace

void detail::decode_camera_json(const std::string& text, const std::string& path, glm::vec3& look, glm::vec3& up) {
    decode_look_up(parse_camera_json(text, path), path, look, up);
}

void detail::decode_camera_json(const std::string& text, const std::string& path, Frame& frame) {
    const nlohmann::json j = parse_camera_json(text, path);
    decode_look_up(j, path, frame.look, frame.up);
    frame.position.reset();
    frame.area_light.reset();
    if (j.contains("position")) frame.position = json_vec3(j, "position", path);
    if (j.contains("area_light")) {
        const nlohmann::json& a = j["area_light"];
        const std::string where = path + " \"area_light\"";
        if (!a.is_object()) throw InputError("read " + where + ": must be an object");
        for (auto it = a.begin(); it != a.end(); ++it)
            if (it.key() != "centre" && it.key() != "half_u" && it.key() != "half_v" && it.key() != "radiance")
                throw InputError("read " + where + ": unknown key \"" + it.key() + "\"");
        AreaLight l;
        l.centre = json_vec3(a, "centre", where);
        l.half_u = json_vec3(a, "half_u", where);
        l.half_v = json_vec3(a, "half_v", where);
        l.radiance = json_vec3(a, "radiance", where);
        check_area_light(l, "read " + path);
        frame.area_light = l;
    }
}

std::size_t FrameReadStats::total_sanitized() const {
    std::size_t n = 0;
    for (const auto& s : sanitized) n += s.nan + s.inf;
    return n;
}

Frame read_frame(const std::string& dir, FrameReadStats* stats) {
    const fs::path root(dir);
    std::error_code ec;
    if (!fs::is_directory(root, ec)) throw InputError("read frame " + dir + ": not a directory");
    FrameReadStats local;
    FrameReadStats& st = stats ? *stats : local;
    st = {};
    Frame frame;
    read_camera(frame, root / "camera.json");

    std::string first;  // the first face file read: the size every other face must have
    for (int fi = 0; fi < kFeatureCount; ++fi) {
        const Feature feature = Feature(fi);
        auto file_base = [&](int k) { return root / (std::string(face_name(Face(k))) + "_" + feature_name(feature)); };
        auto present = [&](int k) {
            return fs::exists(file_base(k).string() + ".exr", ec) ||
                   (png_allowed(feature) && fs::exists(file_base(k).string() + ".png", ec));
        };
        if (optional_feature(feature)) {
            int faces_present = 0;
            for (int k = 0; k < kFaceCount; ++k) faces_present += present(k);
            if (faces_present == 0) continue;  // absent as a whole: allowed
        }
        for (int k = 0; k < kFaceCount; ++k) {
            const fs::path exr = file_base(k).string() + ".exr", png = file_base(k).string() + ".png";
            const bool has_exr = fs::exists(exr, ec), has_png = png_allowed(feature) && fs::exists(png, ec);
            if (!has_exr && !has_png)
                throw InputError("read frame " + dir + ": missing " + exr.string() +
                                 (png_allowed(feature) ? " (or .png)" : "") +
                                 (optional_feature(feature) ? std::string("; ") + feature_name(feature) +
                                                                  " is optional, but then absent on every face"
                                                            : ""));
            if (has_exr && has_png)
                throw InputError("read frame " + dir + ": both " + exr.string() + " and " + png.string() +
                                 " exist; keep one");
            const fs::path file = has_exr ? exr : png;
            const std::string path = file.string();
            std::vector<std::string> names;
            Image img = has_exr ? read_exr(path, &names) : read_png(path);
            if (has_png) st.ldr_files.push_back(file.filename().string());
            img = fit_channels(std::move(img), feature_channels(feature), has_png || names.back() == "A", path);
            if (img.width != img.height)
                throw InputError("read " + path + ": is " + size_string(img) + "; face images must be square");
            if (first.empty()) {
                frame.n = img.width;
                first = path;
            } else if (img.width != frame.n) {
                throw InputError("read " + path + ": is " + size_string(img) + ", but " + first + " is " +
                                 std::to_string(frame.n) + "x" + std::to_string(frame.n) +
                                 "; all faces of a frame have one size");
            }
            sanitize(img, feature, file.filename().string(), path, st);
            frame.get(feature, Face(k)) = std::move(img);
        }
    }

    const fs::path ref = root / "reference.exr";
    if (fs::exists(ref, ec)) {
        std::vector<std::string> names;
        Image img = read_exr(ref.string(), &names);
        img = fit_channels(std::move(img), 3, names.back() == "A", ref.string());
        // The reference is the front view's lighting, pixel for pixel: every consumer (compose, metrics, the
        // training target) pairs it with the N x N front face.
        if (img.width != frame.n || img.height != frame.n)
            throw InputError("read " + ref.string() + ": is " + size_string(img) + ", but the faces (" + first +
                             ") are " + std::to_string(frame.n) + "x" + std::to_string(frame.n) +
                             "; the reference must have the face size");
        sanitize(img, Feature::Direct, "reference.exr", ref.string(), st);
        frame.reference = std::move(img);
    }
    return frame;
}

namespace {

// Everything write_frame checks before touching the disk (sizes, channel counts, the camera, the area light);
// returns which optional features are absent.
std::array<bool, kFeatureCount> validate_frame_for_writing(const std::string& dir, const Frame& frame) {
    const std::string what = "write frame " + dir + ": ";
    // Validate everything before touching the disk.
    if (frame.n <= 0) throw InputError(what + "frame.n is " + std::to_string(frame.n));
    std::array<bool, kFeatureCount> absent{};
    for (int fi = 0; fi < kFeatureCount; ++fi) {
        absent[fi] = optional_feature(Feature(fi)) &&
                     std::all_of(frame.faces[fi].begin(), frame.faces[fi].end(), [](const Image& i) { return is_empty(i); });
        for (int k = 0; k < kFaceCount && !absent[fi]; ++k)
            check_image(frame.get(Feature(fi), Face(k)), feature_channels(Feature(fi)), frame.n,
                        what + face_name(Face(k)) + " " + feature_name(Feature(fi)));
    }
    if (frame.reference) check_image(*frame.reference, 3, frame.n, what + "reference");
    try {
        CameraCluster::from_look_up(frame.look, frame.up);
    } catch (const InputError& e) {
        throw InputError(what + e.what());
    }
    if (frame.position && !(std::isfinite(frame.position->x) && std::isfinite(frame.position->y) &&
                            std::isfinite(frame.position->z)))
        throw InputError(what + "position is not finite");
    if (frame.area_light) check_area_light(*frame.area_light, "write frame " + dir);
    return absent;
}

// The files of a validated frame, into the staging folder of `out`.
void write_frame_into(const OutputFolder& out, const Frame& frame, const std::array<bool, kFeatureCount>& absent) {
    for (int fi = 0; fi < kFeatureCount; ++fi) {
        const Feature f = Feature(fi);
        for (int k = 0; k < kFaceCount && !absent[fi]; ++k) {
            const Image& img = frame.get(f, Face(k));
            ExrPixelType type = ExrPixelType::Float;
            if (f != Feature::Normal && f != Feature::Depth) {
                const bool fits_half = std::all_of(img.data.begin(), img.data.end(),
                                                   [](float v) { return !std::isfinite(v) || std::abs(v) <= 65504.0f; });
                type = fits_half ? ExrPixelType::Half : ExrPixelType::Float;
            }
            out.write(std::string(face_name(Face(k))) + "_" + feature_name(f) + ".exr",
                      [&](const std::string& p) { write_exr(p, img, type); });
        }
    }
    if (frame.reference)
        out.write("reference.exr", [&](const std::string& p) { write_exr(p, *frame.reference, ExrPixelType::Float); });
    nlohmann::json camera = {{"look", {frame.look.x, frame.look.y, frame.look.z}},
                             {"up", {frame.up.x, frame.up.y, frame.up.z}}};
    // Only when present: a frame without them keeps the camera.json it had before these keys existed.
    auto vec = [](glm::vec3 v) { return nlohmann::json::array({v.x, v.y, v.z}); };
    if (frame.position) camera["position"] = vec(*frame.position);
    if (frame.area_light)
        camera["area_light"] = {{"centre", vec(frame.area_light->centre)}, {"half_u", vec(frame.area_light->half_u)},
                                {"half_v", vec(frame.area_light->half_v)},
                                {"radiance", vec(frame.area_light->radiance)}};
    out.write_text("camera.json", camera.dump(2) + "\n");
}

}  // namespace

void write_frame(const std::string& dir, const Frame& frame) {
    const std::array<bool, kFeatureCount> absent = validate_frame_for_writing(dir, frame);  // before the disk
    OutputFolder out(dir, "write frame", frame_folder_replaceable);
    write_frame_into(out, frame, absent);
    out.commit();
}

std::unique_ptr<OutputFolder> frame_output_folder(const std::string& dir) {
    return std::make_unique<OutputFolder>(dir, "write frame", frame_folder_replaceable);
}

void write_frame_files(const OutputFolder& out, const Frame& frame) {
    write_frame_into(out, frame, validate_frame_for_writing(out.target(), frame));
}


}  // namespace ngi
