// A tiny MagicaVoxel .vox writer for the tests: chunks are built by hand so that broken and hostile files can be
// made too (the format: https://github.com/ephtracy/voxel-model). Every helper returns the chunk's bytes.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace vox_test {

inline std::string i32(std::int32_t v) {
    std::string s(4, '\0');
    for (int k = 0; k < 4; ++k) s[k] = char((std::uint32_t(v) >> (8 * k)) & 0xff);
    return s;
}
inline std::string chunk(const std::string& id, const std::string& content, const std::string& children = "") {
    return id + i32(std::int32_t(content.size())) + i32(std::int32_t(children.size())) + content + children;
}
inline std::string str(const std::string& s) { return i32(std::int32_t(s.size())) + s; }
using Dict = std::vector<std::pair<std::string, std::string>>;
inline std::string dict(const Dict& kv) {
    std::string s = i32(std::int32_t(kv.size()));
    for (const auto& [k, v] : kv) s += str(k) + str(v);
    return s;
}
inline std::string size_chunk(int x, int y, int z) { return chunk("SIZE", i32(x) + i32(y) + i32(z)); }
inline std::string xyzi(const std::vector<std::array<int, 4>>& v) {
    std::string s = i32(std::int32_t(v.size()));
    for (const auto& e : v)
        for (int k = 0; k < 4; ++k) s += char(e[k]);
    return chunk("XYZI", s);
}
// Scene graph: a transform (one child, frame 0 given by `frame`, e.g. {{"_t", "1 2 3"}, {"_r", "4"}}), a group
// and a shape (one model).
inline std::string ntrn(int id, int child, const Dict& frame = {}) {
    return chunk("nTRN", i32(id) + dict({}) + i32(child) + i32(-1) + i32(-1) + i32(1) + dict(frame));
}
inline std::string ngrp(int id, const std::vector<int>& children) {
    std::string s = i32(id) + dict({}) + i32(std::int32_t(children.size()));
    for (int c : children) s += i32(c);
    return chunk("nGRP", s);
}
inline std::string nshp(int id, int model) { return chunk("nSHP", i32(id) + dict({}) + i32(1) + i32(model) + dict({})); }
inline std::string vox_file(const std::string& main_children) {
    return "VOX " + i32(150) + chunk("MAIN", "", main_children);
}

}  // namespace vox_test
