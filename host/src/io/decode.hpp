// In-memory decoders behind the file readers: each takes the file's bytes plus the path it came from (used only
// in error messages), so the readers are thin wrappers around read_file and the fuzz targets (fuzz/) can feed
// bytes without touching the disk. Library-internal; the public readers are in ngi/tensor.hpp and ngi/image_io.hpp.
#pragma once
#include <string>
#include <vector>

#include "ngi/image.hpp"
#include "ngi/image_io.hpp"
#include "ngi/tensor.hpp"
#include "base/npy.hpp"  // decode_npy: in ngi_core with read_npy

namespace ngi::detail {

Image decode_exr(const std::string& bytes, const std::string& path, std::vector<std::string>* channel_names = nullptr);
Image decode_png(const std::string& bytes, const std::string& path, PngEncoding encoding = PngEncoding::Linear);

// camera.json of a frame folder: {"look": [x, y, z], "up": [x, y, z]}, validated as a camera cluster.
void decode_camera_json(const std::string& text, const std::string& path, glm::vec3& look, glm::vec3& up);
// The same plus the optional "position" ([x, y, z]) and "area_light" ({"centre", "half_u", "half_v", "radiance"},
// each [x, y, z], validated by check_area_light) into frame.position / frame.area_light (absent keys: empty).
void decode_camera_json(const std::string& text, const std::string& path, Frame& frame);

}  // namespace ngi::detail
