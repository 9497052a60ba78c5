// Planar float images and the frame folder: the data the surround-aware pipeline consumes and the renderer
// produces. Conventions (docs/CONVENTIONS.md): planar CHW, row 0 = top of the image, linear values.
#pragma once
#include <array>
#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ngi/area_light.hpp"
#include "ngi/camera.hpp"

namespace ngi {

// data[(c * height + y) * width + x]; y = 0 is the top row.
struct Image {
    int width = 0, height = 0, channels = 0;
    std::vector<float> data;

    Image() = default;
    Image(int w, int h, int c, float fill = 0.0f) : width(w), height(h), channels(c), data(std::size_t(w) * h * c, fill) {}
    float& at(int c, int y, int x) { return data[(std::size_t(c) * height + y) * width + x]; }
    float at(int c, int y, int x) const { return data[(std::size_t(c) * height + y) * width + x]; }
    std::size_t plane() const { return std::size_t(width) * height; }
};

// Per-face feature buffers of a frame folder (<face>_<feature>.exr).
enum class Feature : int { Albedo = 0, Normal = 1, Depth = 2, Direct = 3, Emission = 4, Env = 5 };
constexpr int kFeatureCount = 6;
const char* feature_name(Feature f);  // "albedo", "normal", "depth", "direct", "emission", "env"
int feature_channels(Feature f);      // 3, 3, 1, 3, 3, 3

// One frame of the camera cluster: every feature of every face (N x N each), the front camera's look/up,
// and optionally the path-traced reference lighting of the front view (direct + indirect diffuse, no albedo).
struct Frame {
    int n = 0;
    glm::vec3 look{0, 0, -1}, up{0, 1, 0};
    std::array<std::array<Image, kFaceCount>, kFeatureCount> faces;  // [feature][face]
    std::optional<Image> reference;
    // The rectangular area light the frame was lit with (absent: none) and the cluster centre in world metres,
    // so that a consumer can place the light relative to each pixel (world position = centre + planar depth along
    // the pixel's ray). Renderer::render records both only when the frame has an area light, which leaves the
    // camera.json of every other frame as it was.
    std::optional<AreaLight> area_light;
    std::optional<glm::vec3> position;
    Image& get(Feature f, Face face) { return faces[int(f)][int(face)]; }
    const Image& get(Feature f, Face face) const { return faces[int(f)][int(face)]; }
};

}  // namespace ngi
