// Wavefront OBJ (+ its .mtl material libraries) -> MeshFile: ngi's own reader, the only parser of the format.
// Read: `v` (x y z, x y z w, or x y z r g b), `vt`, `vn`, `f` / `l` / `p` with indices v, v/vt, v//vn, v/vt/vn
// (1-based; negative = relative to the vertices so far), `usemtl`, `mtllib`, `o` and `g`; other statements (`s`,
// comments, curves) are skipped. Every number is a number (no NaN or Inf reaches the mesh), every index is checked,
// and errors name the line. Faces of one object or group and one material make one part (their identical vertices
// join); a face of 1 or 2 vertices is a point or a line, as `p` and `l` are (counted, dropped).
// Why not tinyobjloader (Debian's 2.0.0rc10): it reads a number it cannot parse ("nan", "1v", "x") as 0 and an
// index past int through atoi (4294967295 becomes -1, a relative index), names a usemtl by its first word but a
// newmtl by its whole line, and cannot tell an absent Kd from Kd 0 0 0 -- each a silently wrong mesh where ngi refuses
// the file.
#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "ngi/host_memory.hpp"
#include "ngi/mesh.hpp"
#include "render/finite.hpp"
#include "render/mesh_source.hpp"

namespace ngi::detail {
namespace {

bool obj_blank(char c) { return c == ' ' || c == '\t'; }

std::string_view obj_trim(std::string_view v) {
    while (!v.empty() && obj_blank(v.front())) v.remove_prefix(1);
    while (!v.empty() && obj_blank(v.back())) v.remove_suffix(1);
    return v;
}

std::vector<std::string_view> obj_words(std::string_view line) {
    std::vector<std::string_view> t;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && obj_blank(line[i])) ++i;
        const std::size_t s = i;
        while (i < line.size() && !obj_blank(line[i])) ++i;
        if (i > s) t.push_back(line.substr(s, i - s));
    }
    return t;
}

// The lines of a text file: at LF, a CR before it dropped. Control characters (other than tab), a lone CR and a
// backslash continuing a line are refused: a file holding them is not the text it claims to be.
template <class F>
void obj_lines(const std::string& b, const std::string& name, const std::string& kind, F&& each) {
    std::size_t pos = 0;
    for (std::uint64_t line_no = 1; pos < b.size(); ++line_no) {
        const std::size_t nl = b.find('\n', pos);
        std::string_view line(b.data() + pos, (nl == std::string::npos ? b.size() : nl) - pos);
        pos = nl == std::string::npos ? b.size() : nl + 1;
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        const std::string at = kind + " line " + std::to_string(line_no) + ": ";
        for (const char ch : line) {
            const unsigned char c = static_cast<unsigned char>(ch);
            if ((c < 0x20 && c != '\t') || c == 0x7f)
                mesh_fail(name, at + "control character " + std::to_string(int(c)) + " (not a text file?)");
        }
        if (!line.empty() && line.back() == '\\') mesh_fail(name, at + "a line continued with a backslash (not supported)");
        const std::size_t hash = line.find('#');
        each(obj_trim(line.substr(0, hash)), at, line_no);
    }
}

// The numbers after a statement's keyword, each a whole number token.
std::vector<double> obj_numbers(const std::vector<std::string_view>& w, const std::string& name, const std::string& at) {
    std::vector<double> out;
    for (std::size_t i = 1; i < w.size(); ++i) {
        double v = 0;
        const auto r = std::from_chars(w[i].data(), w[i].data() + w[i].size(), v);
        if (r.ec == std::errc::invalid_argument || r.ptr != w[i].data() + w[i].size())
            mesh_fail(name, at + "'" + mesh_printable(std::string(w[i])) + "' is not a number");
        // Out of double's range: strtod's value (an overflow is Inf and refused as not finite, an underflow 0).
        out.push_back(r.ec == std::errc::result_out_of_range ? std::strtod(std::string(w[i]).c_str(), nullptr) : v);
    }
    return out;
}

struct ObjCorner {
    std::int64_t v, vt, vn;  // 0-based, -1: none
};

struct ObjPartDraft {
    std::string material;  // usemtl name ("" = none)
    std::uint64_t usemtl_line = 0;
    std::string group;     // the o or g name it began with
    std::vector<ObjCorner> corners;
    std::vector<std::uint32_t> sizes;
    std::size_t dropped = 0;
};

// A material library: `newmtl NAME` (the rest of the line), `Kd` and `Ke` (three numbers each); other statements,
// textures among them, are skipped (ngi reads no texture), as is anything before the first newmtl.
void read_mtl(const std::string& bytes, const std::string& name, const std::string& file,
              std::vector<std::string>& names, std::vector<MeshMaterial>& materials) {
    std::set<std::string> ours;
    bool current = false;
    obj_lines(bytes, name, "material library " + file, [&](std::string_view line, const std::string& at, std::uint64_t) {
        const auto w = obj_words(line);
        if (w.empty()) return;
        if (w[0] == "newmtl") {
            const std::string n(obj_trim(line.substr(6)));
            current = !n.empty() && ours.insert(n).second;
            if (!current) return;  // the first definition of a name wins
            names.push_back(n);
            // A material without Kd: the 0.6 grey such files got before ngi read them itself. Kd is sRGB (mesh_io
            // converts it to linear).
            materials.push_back({true, glm::vec3(0.6f), glm::vec3(0.0f)});
            return;
        }
        if (!current || (w[0] != "Kd" && w[0] != "Ke")) return;
        const std::vector<double> v = obj_numbers(w, name, at);
        if (v.size() != 3) mesh_fail(name, at + std::string(w[0]) + " needs 3 numbers (r g b), not " + std::to_string(v.size()));
        const glm::vec3 c{float(v[0]), float(v[1]), float(v[2])};
        const std::string where = "material '" + mesh_printable(names.back()) + "' (" + file + ")";
        if (w[0] == "Kd") {
            check_colour(name, where + " diffuse colour (Kd)", c);
            materials.back().albedo = c;
        } else {
            materials.back().emission = checked_emission(name, where, c, 1.0);
        }
    });
}

}  // namespace

MeshFile read_obj(const std::string& b, const std::string& name, MeshSidecars& sidecars) {
    // Index tokens the faces may hold in all: a polygon of k corners gives k - 2 triangles.
    constexpr std::uint64_t kMaxCorners = 3 * std::uint64_t(kMaxMeshTriangles);
    std::vector<glm::vec3> v, vn, vc;
    std::vector<glm::vec2> vt;
    std::uint64_t coloured = 0, triangles = 0, corners = 0;
    std::int64_t max_index[3] = {0, 0, 0};
    std::uint64_t max_line[3] = {0, 0, 0};
    const char* kinds[3] = {"vertex", "texture coordinate", "normal"};
    std::vector<ObjPartDraft> drafts(1);
    std::vector<std::pair<std::string, std::uint64_t>> libraries;  // mtllib names, in order, with their lines
    obj_lines(b, name, "OBJ", [&](std::string_view line, const std::string& at, std::uint64_t line_no) {
        const auto w = obj_words(line);
        if (w.empty()) return;
        const std::string_view key = w[0];
        if (key == "v" || key == "vt" || key == "vn") {
            const std::vector<double> x = obj_numbers(w, name, at);
            const std::size_t n = x.size();
            if (key == "v" ? !(n == 3 || n == 4 || n == 6) : key == "vt" ? !(n == 2 || n == 3) : n != 3)
                mesh_fail(name, at + std::to_string(n) + " numbers for a " + std::string(key) +
                                    (key == "v" ? " (3, 4 or 6: x y z [w | r g b])" : key == "vt" ? " (2 or 3)" : " (3)"));
            glm::vec3 p{float(x[0]), float(x[1]), n > 2 ? float(x[2]) : 0.0f};
            if (key == "v" && n == 4) {  // homogeneous
                if (x[3] == 0.0) mesh_fail(name, at + "w is 0 (a point at infinity)");
                p /= float(x[3]);
            }
            if (!finite(p))
                mesh_fail(name, at + (key == "v" ? "position" : key == "vn" ? "normal" : "texture coordinate") +
                                    " is not finite");
            if (key == "vt") return vt.push_back(glm::vec2(p));
            if (key == "vn") return vn.push_back(p);
            if (v.size() >= kMaxMeshVertices)
                mesh_fail(name, at + "more than " + std::to_string(kMaxMeshVertices) + " vertices");
            v.push_back(p);
            const glm::vec3 c = n == 6 ? glm::vec3(float(x[3]), float(x[4]), float(x[5])) : glm::vec3(1.0f);
            if (!finite(c)) mesh_fail(name, at + "colour is not finite");
            coloured += n == 6;
            return vc.push_back(c);
        }
        if (key == "f" || key == "l" || key == "p") {
            ObjPartDraft& d = drafts.back();
            const std::size_t k = w.size() - 1;
            if (k >= 3 && key == "f") triangles += k - 2;
            corners += k;
            if (triangles > kMaxMeshTriangles || corners > kMaxCorners)
                mesh_fail(name, at + "the faces so far make more than " + std::to_string(kMaxMeshTriangles) +
                                    " triangles or " + std::to_string(kMaxCorners) + " corners");
            const std::int64_t counts[3] = {std::int64_t(v.size()), std::int64_t(vt.size()), std::int64_t(vn.size())};
            for (std::size_t i = 1; i < w.size(); ++i) {
                std::string_view tok = w[i];
                std::int64_t idx[3] = {-1, -1, -1};
                for (int part = 0; part < 3 && !tok.empty(); ++part) {  // "v", "v/vt", "v//vn", "v/vt/vn"
                    const std::size_t slash = tok.find('/');
                    const std::string_view s = tok.substr(0, slash);
                    tok = slash == std::string_view::npos ? std::string_view() : tok.substr(slash + 1);
                    if (part == 2 && !tok.empty())  // a trailing slash is allowed
                        mesh_fail(name, at + "'" + mesh_printable(std::string(w[i])) + "' has more than three parts (v/vt/vn)");
                    if (s.empty() && part > 0) continue;
                    std::int64_t x = 0;
                    const auto r = std::from_chars(s.data(), s.data() + s.size(), x);
                    if (r.ec != std::errc() || r.ptr != s.data() + s.size() || x == 0)
                        mesh_fail(name, at + "'" + mesh_printable(std::string(s)) + "' is not a " + kinds[part] + " index");
                    if (x < 0) {
                        if (x < -counts[part])
                            mesh_fail(name, at + "relative " + kinds[part] + " index " + std::to_string(x) +
                                                " reaches before the first of the " + std::to_string(counts[part]) +
                                                " so far");
                        idx[part] = counts[part] + x;
                    } else {
                        idx[part] = x - 1;
                        if (x > max_index[part]) max_index[part] = x, max_line[part] = line_no;
                    }
                }
                if (idx[0] < 0) mesh_fail(name, at + "'" + mesh_printable(std::string(w[i])) + "' has no vertex index");
                if (key == "f" && k >= 3) d.corners.push_back({idx[0], idx[1], idx[2]});
            }
            if (key == "f" && k >= 3) d.sizes.push_back(std::uint32_t(k));
            else d.dropped += key == "p" ? k : key == "l" ? (k > 0 ? k - 1 : 0) : 1;
            return;
        }
        if (key == "usemtl" || key == "o" || key == "g") {
            // A new part at a change of material, or of object or group name (the same name again continues it).
            const std::string rest(obj_trim(line.substr(key.size())));
            ObjPartDraft& d = drafts.back();
            const std::string material = key == "usemtl" ? rest : d.material, group = key == "usemtl" ? d.group : rest;
            if (material == d.material && group == d.group) return;
            if (d.sizes.empty() && d.dropped == 0) {  // nothing in it yet: renamed
                d.material = material;
                d.group = group;
                if (key == "usemtl") d.usemtl_line = line_no;
                return;
            }
            drafts.push_back({material, key == "usemtl" ? line_no : d.usemtl_line, group, {}, {}, 0});
            return;
        }
        if (key == "mtllib") libraries.emplace_back(std::string(obj_trim(line.substr(6))), line_no);
    });
    for (int k = 0; k < 3; ++k)
        if (max_index[k] > std::int64_t(k == 0 ? v.size() : k == 1 ? vt.size() : vn.size()))
            mesh_fail(name, "OBJ line " + std::to_string(max_line[k]) + ": " + kinds[k] + " index " +
                                std::to_string(max_index[k]) + " is out of range (the file has " +
                                std::to_string(k == 0 ? v.size() : k == 1 ? vt.size() : vn.size()) + ")");
    if (coloured != 0 && coloured != v.size())
        mesh_fail(name, "OBJ: " + std::to_string(coloured) + " of its " + std::to_string(v.size()) +
                            " vertices have a colour (x y z r g b): all or none");

    MeshFile out;
    out.format = MeshFormat::Obj;
    // Material libraries (load_mesh: beside the OBJ; parse_mesh reads none, so the faces keep no material colour).
    // One that is not there is refused when no library could be read: the file would load grey, silently.
    std::vector<std::string> names, read, missing;
    if (sidecars.enabled()) {
        const std::filesystem::path dir = std::filesystem::path(name).parent_path();
        for (const auto& [lib, line] : libraries) {
            const std::string path = (dir / lib).string();
            std::error_code ec;
            if (lib.empty() || !std::filesystem::exists(path, ec)) {
                missing.push_back(path);
                continue;
            }
            read_mtl(sidecars.read(path), name, lib, names, out.materials);
            read.push_back(lib);
        }
        if (read.empty() && !missing.empty())
            mesh_fail(name, "its material library " + missing.front() + " does not exist: its colours would be lost (put "
                            "the .mtl beside it, or remove the mtllib line to load it in the default colour)");
    }

    const bool with_colours = coloured != 0;
    check_host_memory("load mesh " + name + ": " + std::to_string(corners) + " face corners",
                      corners * (3 * sizeof(glm::vec3) + sizeof(glm::vec2) + 16));
    for (ObjPartDraft& d : drafts) {
        if (d.sizes.empty() && d.dropped == 0) continue;
        MeshPart p;
        p.dropped_primitives = d.dropped;
        if (!d.material.empty() && !read.empty()) {
            const auto it = std::find(names.begin(), names.end(), d.material);
            if (it == names.end()) {
                std::string files, known;
                for (const std::string& f : read) files += (files.empty() ? "" : ", ") + f;
                for (const std::string& n : names) {
                    if (known.size() > 200) { known += ", ..."; break; }
                    known += (known.empty() ? "" : ", ") + n;
                }
                mesh_fail(name, "OBJ line " + std::to_string(d.usemtl_line) + ": usemtl '" +
                                    mesh_printable(d.material) + "' names no material of its material library (" +
                                    files + " defines " + (known.empty() ? "none" : known) +
                                    "): its faces would lose their colour");
            }
            p.material = int(it - names.begin());
        }
        // One vertex per face corner, as the file's faces state them; identical ones join in mesh_io.
        bool normals = false, texcoords = false;
        for (const ObjCorner& c : d.corners) normals |= c.vn >= 0, texcoords |= c.vt >= 0;
        for (const ObjCorner& c : d.corners) {
            p.corners.push_back(std::uint32_t(p.positions.size()));
            p.positions.push_back(v[std::size_t(c.v)]);
            if (normals) p.normals.push_back(c.vn >= 0 ? vn[std::size_t(c.vn)] : glm::vec3(0.0f));
            if (texcoords) p.texcoords.push_back(c.vt >= 0 ? vt[std::size_t(c.vt)] : glm::vec2(0.0f));
            if (with_colours) p.colours.push_back(vc[std::size_t(c.v)]);
        }
        p.sizes = std::move(d.sizes);
        out.instances.push_back({out.parts.size(), glm::mat4(1.0f)});
        out.parts.push_back(std::move(p));
    }
    return out;
}

}  // namespace ngi::detail
