// Structural checks of mesh files before assimp parses them (mesh_precheck.hpp says why).
#include "render/mesh_precheck.hpp"

#include <algorithm>
#include <cctype>
#include <cfloat>
#include <charconv>
#include <cstring>
#include <deque>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "ngi/error.hpp"
#include "ngi/mesh.hpp"

namespace ngi::detail {
namespace {

using nlohmann::json;

// Index tokens a face may hold in all: every triangle needs 3, and a polygon of k corners gives k - 2 triangles.
constexpr std::uint64_t kMaxMeshIndices = 3 * std::uint64_t(kMaxMeshTriangles);

struct Fail {
    const std::string& name;
    [[noreturn]] void operator()(const std::string& what) const { throw InputError("load mesh " + name + ": " + what); }
};

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

// `s` for an error message: control characters and bytes beyond ASCII as \xNN, at most 40 characters.
std::string printable(std::string_view s) {
    std::string out;
    for (std::size_t i = 0; i < s.size() && i < 40; ++i) {
        const unsigned char c = static_cast<unsigned char>(s[i]);
        if (c >= 0x20 && c < 0x7f) {
            out += char(c);
        } else {
            static const char* hex = "0123456789abcdef";
            out += std::string("\\x") + hex[c >> 4] + hex[c & 15];
        }
    }
    return s.size() > 40 ? out + "..." : out;
}

// Whitespace-separated tokens of one line.
std::vector<std::string_view> tokens(std::string_view line) {
    std::vector<std::string_view> t;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && is_space(line[i])) ++i;
        const std::size_t s = i;
        while (i < line.size() && !is_space(line[i])) ++i;
        if (i > s) t.push_back(line.substr(s, i - s));
    }
    return t;
}

template <class T>
std::optional<T> parse_int(std::string_view s) {
    T v{};
    const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
    if (r.ec != std::errc() || r.ptr != s.data() + s.size()) return std::nullopt;
    return v;
}

// ---- PLY ------------------------------------------------------------------------------------------------------
// The header declares every element's count and the types of its properties, so the bytes the body needs are known
// before it is read. Both encodings are walked element by element (lists read their own counts), which is also
// what bounds assimp's list allocations: no list may claim more items than the bytes (or tokens) left.

struct PlyProperty {
    bool list = false;
    int size = 0;        // bytes of the scalar, or of the list's items
    int count_size = 0;  // bytes of the list's count
    bool count_signed = false;
    bool count_float = false;
    std::string name;
};

struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> props;
};

// Bytes of a PLY scalar type, 0 if it is not one. `is_signed` / `is_float` describe it.
int ply_type_size(std::string_view t, bool* is_signed = nullptr, bool* is_float = nullptr) {
    struct Type { const char* a; const char* b; int size; bool sign, flt; };
    static const Type types[] = {{"char", "int8", 1, true, false},     {"uchar", "uint8", 1, false, false},
                                 {"short", "int16", 2, true, false},   {"ushort", "uint16", 2, false, false},
                                 {"int", "int32", 4, true, false},     {"uint", "uint32", 4, false, false},
                                 {"float", "float32", 4, true, true},  {"double", "float64", 8, true, true}};
    for (const Type& x : types)
        if (t == x.a || t == x.b) {
            if (is_signed) *is_signed = x.sign;
            if (is_float) *is_float = x.flt;
            return x.size;
        }
    return 0;
}

bool is_face_element(const std::string& n) { return n == "face"; }

void check_ply(const std::string& b, const Fail& fail) {
    // The header: text lines up to "end_header". 64 KiB is far more than any real header (a few hundred bytes).
    constexpr std::size_t kMaxHeader = 64 * 1024;
    std::vector<PlyElement> elements;
    enum class Format { Ascii, Little, Big } format = Format::Ascii;
    bool have_format = false;
    std::size_t pos = 0, body = std::string::npos;
    for (int line_no = 0; pos < b.size(); ++line_no) {
        if (pos > kMaxHeader) fail("PLY header longer than 64 KiB (no end_header)");
        const std::size_t nl = b.find('\n', pos);
        const std::string_view line(b.data() + pos, (nl == std::string::npos ? b.size() : nl) - pos);
        pos = nl == std::string::npos ? b.size() : nl + 1;
        for (char ch : line)
            if ((static_cast<unsigned char>(ch) < 0x20 && ch != '\t' && ch != '\r') || ch == 0x7f)
                fail("PLY header line " + std::to_string(line_no + 1) + ": control character (not a text header)");
        const auto t = tokens(line);
        if (line_no == 0) {
            if (t.size() != 1 || (t[0] != "ply" && t[0] != "PLY")) fail("not a PLY file (no \"ply\" first line)");
            continue;
        }
        if (t.empty() || t[0] == "comment" || t[0] == "obj_info") continue;
        if (t[0] == "end_header") {
            body = pos;
            break;
        }
        if (t[0] == "format") {
            if (t.size() < 2) fail("PLY header: bad format line");
            if (t[1] == "ascii") format = Format::Ascii;
            else if (t[1] == "binary_little_endian") format = Format::Little;
            else if (t[1] == "binary_big_endian") format = Format::Big;
            else fail("PLY header: unknown format '" + std::string(t[1]) + "'");
            have_format = true;
        } else if (t[0] == "element") {
            if (t.size() != 3) fail("PLY header: bad element line on header line " + std::to_string(line_no + 1));
            const auto n = parse_int<std::uint64_t>(t[2]);
            if (!n) fail("PLY header: element '" + std::string(t[1]) + "' count '" + std::string(t[2]) +
                         "' is not a non-negative integer");
            // assimp 5.2.5 reads a tristrips element wrongly (one triangle per strip) and leaks its indices:
            // refused rather than loaded wrong. Real PLY files (scans, exporters) write faces.
            if (t[1] == "tristrips") fail("PLY tristrips elements are not supported (write faces)");
            // assimp 5.2.5 sizes the mesh's vertex (face) array by the first vertex (face) element and writes every
            // later one's at the same indices: a second, longer one writes past the array (valgrind: "Invalid write
            // ... 0 bytes after a block"; through parse_mesh, glibc aborted on a corrupted heap). Upstream checks
            // since (assimp PR 5739).
            if (t[1] == "vertex" || t[1] == "face")
                for (const auto& e : elements)
                    if (e.name == t[1])
                        fail("PLY header: a second '" + std::string(t[1]) + "' element on header line " +
                             std::to_string(line_no + 1) + " (one of each is supported)");
            elements.push_back({std::string(t[1]), *n, {}});
            const std::uint64_t limit = elements.back().name == "vertex" ? kMaxMeshVertices : kMaxMeshTriangles;
            // Every element is a vertex, a face or something else the same size or larger: the triangle limit
            // bounds them all (2^24 is both limits).
            if (*n > limit)
                fail("PLY header claims " + std::to_string(*n) + " elements '" + elements.back().name +
                     "', more than the limit of " + std::to_string(limit));
        } else if (t[0] == "property") {
            if (elements.empty()) fail("PLY header: property before any element");
            PlyProperty p;
            if (t.size() == 5 && t[1] == "list") {
                p.list = true;
                p.count_size = ply_type_size(t[2], &p.count_signed, &p.count_float);
                p.size = ply_type_size(t[3]);
                p.name = std::string(t[4]);
                if (p.count_size == 0 || p.size == 0 || p.count_float)
                    fail("PLY header: bad list types of property '" + p.name + "'");
            } else if (t.size() == 3) {
                p.size = ply_type_size(t[1]);
                p.name = std::string(t[2]);
                if (p.size == 0)
                    fail("PLY header: unknown type '" + std::string(t[1]) + "' of property '" + p.name + "'");
            } else {
                fail("PLY header: bad property line on header line " + std::to_string(line_no + 1));
            }
            elements.back().props.push_back(p);
        } else {
            fail("PLY header: unknown keyword '" + std::string(t[0]) + "' on header line " +
                 std::to_string(line_no + 1));
        }
    }
    if (body == std::string::npos) fail("PLY header has no end_header (truncated)");
    if (!have_format) fail("PLY header has no format line");
    for (const auto& e : elements)
        if (e.count > 0 && e.props.empty()) fail("PLY element '" + e.name + "' has no properties");
    // A triangle mesh: vertices with x, y, z and faces with a vertex-index list. Anything else has no triangle to
    // load, and assimp's paths for it (point clouds, vertices without a coordinate) leak what they allocated
    // (fuzz_mesh): refused here instead.
    auto find = [&](const std::string& element, const std::string& property, bool list) {
        for (const auto& e : elements)
            if (e.name == element)
                for (const auto& p : e.props)
                    if (p.name == property && p.list == list) return true;
        return false;
    };
    for (const char* c : {"x", "y", "z"})
        if (!find("vertex", c, false)) fail(std::string("PLY has no vertex element with a scalar property ") + c);
    if (!find("face", "vertex_indices", true) && !find("face", "vertex_index", true))
        fail("PLY has no face element with a vertex_indices list (a point cloud has no triangles)");

    // The least the body can hold: each scalar once, each list's count (binary), or one character and a separator
    // per value (text). Checked first, so a short file claiming millions of elements is refused without a walk.
    const std::uint64_t left = b.size() - body;
    std::uint64_t least = 0;
    for (const auto& e : elements) {
        std::uint64_t per = 0;
        for (const auto& p : e.props)
            per += format == Format::Ascii ? 2 : std::uint64_t(p.list ? p.count_size : p.size);
        least += per * e.count;  // <= 2^24 elements x (16 bytes x properties): no overflow for sane property counts
    }
    if (least > left + 1)
        fail("PLY body needs at least " + std::to_string(least) + " bytes for the elements its header declares, the "
             "file has " + std::to_string(left) + " (truncated, or counts that are not true)");

    std::uint64_t triangles = 0;
    auto add_polygon = [&](const PlyElement& e, std::uint64_t i, std::uint64_t k) {
        if (!is_face_element(e.name)) return;
        if (k >= 3) triangles += k - 2;
        if (triangles > kMaxMeshTriangles)
            fail("PLY " + e.name + " " + std::to_string(i) + ": the faces so far make more than " +
                 std::to_string(kMaxMeshTriangles) + " triangles");
    };
    if (format == Format::Ascii) {
        std::size_t p = body;
        for (const auto& e : elements)
            for (std::uint64_t i = 0; i < e.count; ++i) {
                std::vector<std::string_view> t;
                while (t.empty()) {  // one element per line; blank lines are skipped
                    if (p >= b.size())
                        fail("PLY body ends at " + e.name + " " + std::to_string(i) + " of " + std::to_string(e.count) +
                             " (truncated)");
                    const std::size_t nl = b.find('\n', p);
                    t = tokens(std::string_view(b.data() + p, (nl == std::string::npos ? b.size() : nl) - p));
                    p = nl == std::string::npos ? b.size() : nl + 1;
                }
                // Every value a number: assimp's text parser fails on anything else, and its failure path leaks
                // the mesh it had begun (fuzz_mesh).
                for (std::string_view tok : t) {
                    double v;
                    const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), v);
                    if (r.ec == std::errc::invalid_argument || r.ptr != tok.data() + tok.size())
                        fail("PLY " + e.name + " " + std::to_string(i) + ": '" + printable(tok) + "' is not a number");
                }
                std::size_t k = 0;
                for (const auto& prop : e.props) {
                    if (k >= t.size())
                        fail("PLY " + e.name + " " + std::to_string(i) + ": property '" + prop.name + "' is missing");
                    if (!prop.list) { ++k; continue; }
                    const auto n = parse_int<std::uint64_t>(t[k]);
                    if (!n || *n > t.size() - k - 1)
                        fail("PLY " + e.name + " " + std::to_string(i) + ": list '" + prop.name + "' claims " +
                             std::string(t[k]) + " items, the line has " + std::to_string(t.size() - k - 1) + " left");
                    add_polygon(e, i, *n);
                    k += 1 + std::size_t(*n);
                }
            }
        return;
    }
    const bool big = format == Format::Big;
    std::size_t p = body;
    auto read_count = [&](const PlyProperty& prop) -> std::int64_t {
        std::uint64_t v = 0;
        for (int k = 0; k < prop.count_size; ++k) {
            const unsigned char c = static_cast<unsigned char>(b[p + std::size_t(big ? k : prop.count_size - 1 - k)]);
            v = v << 8 | c;
        }
        p += std::size_t(prop.count_size);
        if (prop.count_signed && (v >> (8 * prop.count_size - 1)) & 1) return -1;  // negative
        return std::int64_t(v);
    };
    for (const auto& e : elements)
        for (std::uint64_t i = 0; i < e.count; ++i)
            for (const auto& prop : e.props) {
                const std::size_t need = std::size_t(prop.list ? prop.count_size : prop.size);
                if (b.size() - p < need)
                    fail("PLY body ends in " + e.name + " " + std::to_string(i) + " of " + std::to_string(e.count) +
                         " (truncated)");
                if (!prop.list) { p += need; continue; }
                const std::int64_t n = read_count(prop);
                if (n < 0 || std::uint64_t(n) > (b.size() - p) / std::uint64_t(prop.size))
                    fail("PLY " + e.name + " " + std::to_string(i) + ": list '" + prop.name + "' claims " +
                         std::to_string(n) + " items, more than the " + std::to_string(b.size() - p) +
                         " bytes left hold");
                add_polygon(e, i, std::uint64_t(n));
                p += std::size_t(n) * std::size_t(prop.size);
            }
}

// ---- OBJ ------------------------------------------------------------------------------------------------------
// No header: the counts are the lines themselves. One pass counts vertices and the triangles the faces make, and
// checks every index (1-based, negative = relative to the vertices so far; 0 is not an index) against the vertices,
// texture coordinates and normals the file has.

void check_obj(const std::string& b, const Fail& fail) {
    // Text only: control characters other than tab, and a carriage return anywhere but before a line feed, would
    // make assimp split lines where this scan does not (it ends a line at a lone CR), so that the two would count
    // different vertices (fuzz_mesh: an index this scan passed was out of range for assimp, whose error path
    // leaks). A backslash continuing a line is refused for the same reason.
    for (std::size_t i = 0, line = 1; i < b.size(); ++i) {
        const unsigned char c = static_cast<unsigned char>(b[i]);
        if (c == '\n') { ++line; continue; }
        if ((c < 0x20 && c != '\t' && !(c == '\r' && i + 1 < b.size() && b[i + 1] == '\n')) || c == 0x7f)
            fail("OBJ line " + std::to_string(line) + ": control character " + std::to_string(int(c)) +
                 " (not a text file?)");
        const std::string_view rest(b.data() + i + 1, std::min<std::size_t>(2, b.size() - i - 1));
        if (c == '\\' && (rest.empty() || rest[0] == '\n' || rest == "\r\n"))
            fail("OBJ line " + std::to_string(line) + ": a line continued with a backslash (not supported)");
    }
    std::uint64_t counts[3] = {0, 0, 0};           // v, vt, vn
    std::uint64_t max_index[3] = {0, 0, 0}, max_line[3] = {0, 0, 0};
    std::uint64_t triangles = 0, indices = 0;
    const char* kinds[3] = {"vertex", "texture coordinate", "normal"};
    std::size_t pos = 0;
    for (std::uint64_t line_no = 1; pos < b.size(); ++line_no) {
        const std::size_t nl = b.find('\n', pos);
        const std::string_view line(b.data() + pos, (nl == std::string::npos ? b.size() : nl) - pos);
        pos = nl == std::string::npos ? b.size() : nl + 1;
        std::size_t s = 0;
        while (s < line.size() && is_space(line[s])) ++s;
        if (s + 1 >= line.size()) continue;
        const char c0 = line[s], c1 = line[s + 1];
        if (c0 == 'v' && (is_space(c1) || ((c1 == 't' || c1 == 'n') && s + 2 < line.size() && is_space(line[s + 2])))) {
            // As many numbers as assimp takes, all numbers: a vertex line it would skip (5 numbers, say) shifts
            // every later index by one against this count (fuzz_mesh; assimp's error path then leaks).
            const int k = c1 == 't' ? 1 : c1 == 'n' ? 2 : 0;
            std::string_view rest = line.substr(s + (k ? 2 : 1));
            rest = rest.substr(0, rest.find('#'));
            const auto t = tokens(rest);
            for (std::string_view tok : t) {
                double v;
                const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), v);
                if (r.ec == std::errc::invalid_argument || r.ptr != tok.data() + tok.size())
                    fail("OBJ line " + std::to_string(line_no) + ": '" + printable(tok) + "' is not a number");
            }
            const std::size_t n = t.size();
            if (k == 0 ? !(n == 3 || n == 4 || n == 6) : k == 1 ? !(n == 2 || n == 3) : n != 3)
                fail("OBJ line " + std::to_string(line_no) + ": " + std::to_string(n) + " numbers for a " + kinds[k] +
                     (k == 0 ? " (3, 4 or 6: x y z [w | r g b])" : k == 1 ? " (2 or 3)" : " (3)"));
            ++counts[k];
            continue;
        }
        // assimp takes every line starting with f, l or p for a face, line or point ("fnf 612 5" included):
        // so does this scan, and its strict index syntax refuses what is not one.
        if (!(c0 == 'f' || c0 == 'l' || c0 == 'p')) continue;
        const auto t = tokens(line.substr(s + 1));
        // A line element of one vertex is no line: after a material switch, assimp 5.2.5 leaks the meshes it built
        // when it meets one (fuzz_mesh, 807,213th input of the round-two campaign: usemtl, l 2 1, usemtl, l 2).
        if (c0 == 'l' && t.size() < 2)
            fail("OBJ line " + std::to_string(line_no) + ": a line element needs 2 or more vertices, this one has " +
                 std::to_string(t.size()));
        if (c0 == 'f' && t.size() >= 3) triangles += t.size() - 2;
        indices += t.size();
        if (triangles > kMaxMeshTriangles)
            fail("OBJ line " + std::to_string(line_no) + ": the faces so far make more than " +
                 std::to_string(kMaxMeshTriangles) + " triangles");
        if (indices > kMaxMeshIndices)
            fail("OBJ line " + std::to_string(line_no) + ": more than " + std::to_string(kMaxMeshIndices) + " indices");
        for (std::string_view tok : t) {
            // A number after the third slash-separated part is one assimp 5.2.5 does not take: it ends the statement
            // there (ObjFileParser::reportErrorTokenInFace skips to the next line; its reader then continues from
            // bytes left in its line buffer), so "l 1/1/1/1 2" becomes a line of one vertex. Its
            // vertex count then falls short of the indices it writes, and a later line writes 12 bytes past its
            // vertex array (createVertexArray's unchecked mVertices[newIndex + 1]): found by valgrind behind
            // fuzz_mesh's unexplained ASan heap-metadata report (docs/RELIABILITY.md). The position is assimp's:
            // one more per '/', and a number in the texture coordinate's place moves to the normal's when there are
            // normals but no texture coordinates so far ("1/2/3" is then a number in the fourth place).
            {
                const bool shifted = counts[1] == 0 && counts[2] > 0;
                int position = 0;
                for (std::size_t i = 0; i < tok.size(); ++i) {
                    if (tok[i] == '/') {
                        ++position;
                        continue;
                    }
                    if (i > 0 && tok[i - 1] != '/') continue;  // inside the number
                    if (position == 1 && shifted) position = 2;
                    if (position >= 3)
                        fail("OBJ line " + std::to_string(line_no) + ": '" + printable(tok) +
                             "' has a number past its vertex/texture/normal parts (assimp would end the statement "
                             "there)");
                }
            }
            for (int k = 0; k < 3 && !tok.empty(); ++k) {  // "v", "v/vt", "v//vn", "v/vt/vn"
                const std::size_t slash = tok.find('/');
                const std::string_view part = tok.substr(0, slash);
                tok = slash == std::string_view::npos ? std::string_view() : tok.substr(slash + 1);
                if (part.empty() && k > 0) continue;
                const auto v = parse_int<std::int64_t>(part);
                // No leading zero: assimp steps over a number by its value's digits, not the text's, so "010" reads
                // as 10 and then 0 (an exception inside assimp), "01" as 1 twice.
                const std::size_t d = !part.empty() && part[0] == '-' ? 1 : 0;
                if (!v || *v == 0 || (part.size() > d + 1 && part[d] == '0'))
                    fail("OBJ line " + std::to_string(line_no) + ": '" + std::string(part) + "' is not a " + kinds[k] +
                         " index");
                if (*v < 0) {
                    if (std::uint64_t(-(*v + 1)) >= counts[k])
                        fail("OBJ line " + std::to_string(line_no) + ": relative " + kinds[k] + " index " +
                             std::string(part) + " reaches before the first of the " + std::to_string(counts[k]) +
                             " so far");
                } else if (std::uint64_t(*v) > max_index[k]) {
                    max_index[k] = std::uint64_t(*v);
                    max_line[k] = line_no;
                }
            }
        }
    }
    if (counts[0] > kMaxMeshVertices)
        fail(std::to_string(counts[0]) + " vertices, more than the limit of " + std::to_string(kMaxMeshVertices));
    for (int k = 0; k < 3; ++k)
        if (max_index[k] > counts[k])
            fail("OBJ line " + std::to_string(max_line[k]) + ": " + kinds[k] + " index " +
                 std::to_string(max_index[k]) + " is out of range (the file has " + std::to_string(counts[k]) + ")");
}

// ---- MTL (an OBJ's material library) ---------------------------------------------------------------------------
// assimp 5.2.5's material reader writes a texture statement (map_Kd, bump, disp, norm, ...) into "the current
// material" without checking that there is one: a texture line before the first `newmtl` dereferences a null
// material and crashes the process (fuzz_mesh, 811,578th input of the round-two campaign: an OBJ naming itself as
// its `mtllib`, with a bare `map_ns` line). Such a line has no material to apply to, so it is refused. Lines are
// split as assimp splits them (at LF, CR, NUL and form feed; leading blanks skipped) and matched without regard to
// case, which refuses a little more than assimp would crash on (a first line with leading blanks, `MAP_KD`), never
// less. assimp starts a material at any line whose first two characters are `N`/`n` then `e`: so does this scan.

void check_mtl_statements(const std::string& b, const std::string& kind, const Fail& fail) {
    static constexpr std::string_view kTextureStatements[] = {
        "map_kd", "map_ka", "map_ks", "map_disp", "disp", "map_d", "map_emissive", "map_ke", "map_bump", "bump",
        "map_kn", "norm", "refl", "map_ns", "map_pr", "map_pm", "map_ps"};
    const auto line_end = [](char c) { return c == '\n' || c == '\r' || c == '\0' || c == '\f'; };
    std::size_t pos = 0;
    for (std::uint64_t line_no = 1; pos < b.size(); ++line_no) {
        std::size_t end = pos;
        while (end < b.size() && !line_end(b[end])) ++end;
        std::size_t s = pos;
        while (s < end && (b[s] == ' ' || b[s] == '\t')) ++s;
        const std::string_view line(b.data() + s, end - s);
        pos = end + 1;
        if (line.size() >= 2 && (line[0] == 'N' || line[0] == 'n') && line[1] == 'e') return;  // a material exists
        for (std::string_view t : kTextureStatements) {
            if (line.size() < t.size()) continue;
            bool same = true;
            for (std::size_t i = 0; i < t.size() && same; ++i)
                same = std::tolower(static_cast<unsigned char>(line[i])) == t[i];
            if (same)
                fail(kind + " line " + std::to_string(line_no) + ": texture statement '" +
                     printable(line.substr(0, line.find_first_of(" \t"))) +
                     "' before any newmtl (a material statement needs a material to apply to)");
        }
    }
}

// ---- glTF 2.0 -------------------------------------------------------------------------------------------------
// Accessors say how many elements they hold and where: each must lie inside its buffer view, each view inside its
// buffer, each buffer inside the bytes that back it (the GLB's BIN chunk, a data: URI, an external file). Accessors
// without a view (zeros, or sparse) have no bytes to be checked against: together they may claim at most 16 times
// the file's size. The node graph must be a forest (one parent per node, no cycles) at most 64 deep: assimp
// walks it recursively.

constexpr int kMaxGltfDepth = 64;

std::uint32_t le32(const std::string& b, std::size_t at) {
    std::uint32_t v = 0;
    for (int k = 3; k >= 0; --k) v = v << 8 | static_cast<unsigned char>(b[at + std::size_t(k)]);
    return v;
}

// The nesting depth of JSON text (brackets outside strings): refused beyond a bound before any parser recurses.
void check_json_depth(std::string_view j, const Fail& fail) {
    int depth = 0;
    bool in_string = false;
    for (std::size_t i = 0; i < j.size(); ++i) {
        const char c = j[i];
        if (in_string) {
            if (c == '\\') ++i;
            else if (c == '"') in_string = false;
        } else if (c == '"') {
            in_string = true;
        } else if (c == '[' || c == '{') {
            if (++depth > 2 * kMaxGltfDepth) fail("glTF JSON nested deeper than " + std::to_string(2 * kMaxGltfDepth));
        } else if (c == ']' || c == '}') {
            --depth;
        }
    }
}

// Bytes of a glTF componentType, 0 if it is not one.
int component_bytes(std::uint64_t ct) {
    switch (ct) {
        case 5120: case 5121: return 1;  // (unsigned) byte
        case 5122: case 5123: return 2;  // (unsigned) short
        case 5125: case 5126: return 4;  // unsigned int, float
        default: return 0;
    }
}

// Components of a glTF accessor type, 0 if it is not one.
int type_components(const std::string& t) {
    if (t == "SCALAR") return 1;
    if (t == "VEC2") return 2;
    if (t == "VEC3") return 3;
    if (t == "VEC4" || t == "MAT2") return 4;
    if (t == "MAT3") return 9;
    if (t == "MAT4") return 16;
    return 0;
}

struct GltfChecker {
    const json& doc;
    const Fail& fail;
    std::uint64_t input_bytes;

    // doc[key] as an array (absent = empty).
    const json& array(const json& j, const char* key, const std::string& where) const {
        static const json empty = json::array();
        if (!j.is_object() || !j.contains(key)) return empty;
        const json& a = j[key];
        if (!a.is_array()) fail(where + "'" + key + "' is not an array");
        return a;
    }
    // A non-negative integer member, or `fallback` when absent.
    std::uint64_t uint(const json& j, const char* key, const std::string& where, std::uint64_t fallback,
                       bool required = false) const {
        if (!j.contains(key)) {
            if (required) fail(where + " has no '" + key + "'");
            return fallback;
        }
        const json& v = j[key];
        if (!v.is_number_unsigned()) fail(where + " '" + key + "' is not a non-negative integer");
        return v.get<std::uint64_t>();
    }
    std::uint64_t index(const json& j, const char* key, const std::string& where, std::size_t n,
                        const char* of_what) const {
        const std::uint64_t i = uint(j, key, where, 0, true);
        if (i >= n) fail(where + " '" + key + "' " + std::to_string(i) + " is out of range (" + std::to_string(n) +
                         " " + of_what + ")");
        return i;
    }
    std::uint64_t index_value(const json& v, const std::string& where, std::size_t n, const char* of_what) const {
        if (!v.is_number_unsigned() || v.get<std::uint64_t>() >= n)
            fail(where + " refers to " + v.dump() + ", not one of the " + std::to_string(n) + " " + of_what);
        return v.get<std::uint64_t>();
    }
};

// The payload of a data: URI (base64 decoded), nullopt when `uri` is not one. A payload that is not base64 (rare:
// percent-encoded bytes) is returned undecoded: its size is an upper bound, its index values are not checked.
std::optional<std::string> data_uri(const std::string& uri, bool* decoded) {
    if (uri.compare(0, 5, "data:") != 0) return std::nullopt;
    const std::size_t comma = uri.find(',');
    *decoded = false;
    if (comma == std::string::npos) return std::string();
    if (uri.rfind(";base64", comma) == std::string::npos) return uri.substr(comma + 1);
    std::string out;
    out.reserve((uri.size() - comma) / 4 * 3);
    std::uint32_t acc = 0;
    int bits = 0;
    for (std::size_t i = comma + 1; i < uri.size(); ++i) {
        const char c = uri[i];
        const int v = c >= 'A' && c <= 'Z'   ? c - 'A'
                      : c >= 'a' && c <= 'z' ? c - 'a' + 26
                      : c >= '0' && c <= '9' ? c - '0' + 52
                      : c == '+'             ? 62
                      : c == '/'             ? 63
                                             : -1;
        if (v < 0) continue;  // padding; a decoder more lenient than assimp's only overestimates the bytes
        acc = acc << 6 | std::uint32_t(v);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            out += char(acc >> bits & 0xff);
        }
    }
    *decoded = true;
    return out;
}

// Every glTF material's KHR_materials_emissive_strength (1 where it has none): assimp 5.2.5 does not read the
// extension, so mesh_io applies these itself. A strength that is not a finite number >= 0 is refused here.
std::vector<float> gltf_emissive_strengths(const GltfChecker& g, const json& doc, const Fail& fail) {
    const json& materials = g.array(doc, "materials", "glTF ");
    std::vector<float> strengths(materials.size(), 1.0f);
    for (std::size_t i = 0; i < materials.size(); ++i) {
        const json& m = materials[i];
        if (!m.is_object() || !m.contains("extensions") || !m["extensions"].is_object() ||
            !m["extensions"].contains("KHR_materials_emissive_strength"))
            continue;
        const json& e = m["extensions"]["KHR_materials_emissive_strength"];
        if (!e.is_object() || !e.contains("emissiveStrength")) continue;  // the extension's default: 1
        const json& v = e["emissiveStrength"];
        const std::string where = "glTF material " + std::to_string(i) + " KHR_materials_emissive_strength";
        if (!v.is_number()) fail(where + " emissiveStrength is not a number");
        const double d = v.get<double>();
        if (!(d >= 0.0 && d <= double(FLT_MAX)))  // also false for NaN
            fail(where + " emissiveStrength " + v.dump() + " is not a finite number >= 0");
        strengths[i] = float(d);
    }
    return strengths;
}

void check_gltf(const std::string& b, bool binary, const Fail& fail, const SidecarBytes& sidecar,
                MeshPrecheckFacts* facts) {
    std::string_view text;
    std::uint64_t bin_bytes = 0, bin_at = 0;
    bool has_bin = false;
    if (binary) {
        if (b.size() < 20 || b.compare(0, 4, "glTF") != 0) fail("not a GLB file (no \"glTF\" header)");
        if (le32(b, 4) != 2) fail("GLB version " + std::to_string(le32(b, 4)) + " (only 2 is glTF 2.0)");
        const std::uint64_t length = le32(b, 8);
        if (length < 20) fail("GLB header length " + std::to_string(length) + " is shorter than its headers");
        if (length > b.size()) fail("GLB header length " + std::to_string(length) + " is beyond the file's " +
                                    std::to_string(b.size()) + " bytes (truncated)");
        const std::uint64_t json_len = le32(b, 12);
        if (le32(b, 16) != 0x4E4F534Au) fail("GLB: the first chunk is not JSON");
        if (json_len > length - 20) fail("GLB JSON chunk of " + std::to_string(json_len) + " bytes runs past the file");
        text = std::string_view(b.data() + 20, json_len);
        const std::uint64_t next = 20 + ((json_len + 3) & ~std::uint64_t(3));
        if (next + 8 <= length && le32(b, std::size_t(next) + 4) == 0x004E4942u) {
            bin_bytes = le32(b, std::size_t(next));
            bin_at = next + 8;
            if (bin_bytes > length - next - 8)
                fail("GLB BIN chunk of " + std::to_string(bin_bytes) + " bytes runs past the file (truncated)");
            has_bin = true;
        }
    } else {
        text = b;
    }
    check_json_depth(text, fail);
    const json doc = json::parse(text.begin(), text.end(), nullptr, false);
    if (doc.is_discarded() || !doc.is_object()) fail("glTF JSON does not parse");
    if (!doc.contains("asset") || !doc["asset"].is_object() || !doc["asset"].contains("version") ||
        !doc["asset"]["version"].is_string() || doc["asset"]["version"].get<std::string>().compare(0, 2, "2.") != 0)
        fail("not glTF 2.0 (asset.version is not \"2.x\")");
    const GltfChecker g{doc, fail, b.size()};
    std::vector<float> strengths = gltf_emissive_strengths(g, doc, fail);  // checked with or without `facts`
    if (facts) facts->gltf_emissive_strength = std::move(strengths);

    const json& buffers = g.array(doc, "buffers", "glTF ");
    std::vector<std::uint64_t> buffer_len;
    std::vector<std::string_view> buffer_bytes;  // empty view: bytes not known (undecoded data: URI)
    std::deque<std::string> decoded;             // data: URI payloads, for the index check below
    for (std::size_t i = 0; i < buffers.size(); ++i) {
        const std::string where = "glTF buffer " + std::to_string(i);
        const std::uint64_t n = g.uint(buffers[i], "byteLength", where, 0, true);
        std::string_view bytes;
        std::uint64_t backed = 0;
        if (!buffers[i].is_object() || !buffers[i].contains("uri")) {
            if (!(binary && i == 0 && has_bin)) fail(where + " has no uri and no GLB BIN chunk");
            backed = bin_bytes;
            bytes = std::string_view(b.data() + bin_at, bin_bytes);
        } else {
            if (!buffers[i]["uri"].is_string()) fail(where + " uri is not a string");
            const std::string uri = buffers[i]["uri"].get<std::string>();
            bool is_decoded = false;
            if (auto d = data_uri(uri, &is_decoded)) {
                decoded.push_back(std::move(*d));
                backed = decoded.back().size();
                if (is_decoded) bytes = decoded.back();
            } else {
                const std::string& file = sidecar(uri);
                backed = file.size();
                bytes = file;
            }
        }
        if (n > backed)
            fail(where + " byteLength " + std::to_string(n) + " is more than the " + std::to_string(backed) +
                 " bytes behind it");
        buffer_len.push_back(n);
        buffer_bytes.push_back(bytes.substr(0, bytes.empty() ? 0 : n));
    }
    const json& views = g.array(doc, "bufferViews", "glTF ");
    std::vector<std::uint64_t> view_len;
    for (std::size_t i = 0; i < views.size(); ++i) {
        const std::string where = "glTF bufferView " + std::to_string(i);
        const std::uint64_t buf = g.index(views[i], "buffer", where, buffer_len.size(), "buffers");
        const std::uint64_t off = g.uint(views[i], "byteOffset", where, 0);
        const std::uint64_t len = g.uint(views[i], "byteLength", where, 0, true);
        if (off > buffer_len[buf] || len > buffer_len[buf] - off)
            fail(where + " (offset " + std::to_string(off) + ", " + std::to_string(len) + " bytes) runs past buffer " +
                 std::to_string(buf) + " (" + std::to_string(buffer_len[buf]) + " bytes)");
        const std::uint64_t stride = g.uint(views[i], "byteStride", where, 0);
        if (stride > 252) fail(where + " byteStride " + std::to_string(stride) + " is more than glTF's 252");
        view_len.push_back(len);
    }
    // Bytes claimed by accessors without a view: bounded in total (see above).
    std::uint64_t unbacked = 0;
    const std::uint64_t unbacked_limit = 16 * g.input_bytes + (std::uint64_t(1) << 20);
    const json& accessors = g.array(doc, "accessors", "glTF ");
    auto check_in_view = [&](const json& owner, const std::string& where, std::uint64_t count, std::uint64_t elem) {
        const std::uint64_t v = g.index(owner, "bufferView", where, view_len.size(), "buffer views");
        const std::uint64_t off = g.uint(owner, "byteOffset", where, 0);
        if (off > view_len[v])
            fail(where + " byteOffset " + std::to_string(off) + " is past buffer view " + std::to_string(v));
        const std::uint64_t stride =
            std::max(g.uint(views[v], "byteStride", "glTF bufferView " + std::to_string(v), 0), elem);
        // count <= 3 x 2^24, stride <= 252, off <= a view's length: no overflow.
        const std::uint64_t need = off + (count - 1) * stride + elem;
        if (count > 0 && need > view_len[v])
            fail(where + ": " + std::to_string(count) + " elements need " + std::to_string(need) +
                 " bytes, buffer view " + std::to_string(v) + " has " + std::to_string(view_len[v]));
    };
    for (std::size_t i = 0; i < accessors.size(); ++i) {
        const json& a = accessors[i];
        const std::string where = "glTF accessor " + std::to_string(i);
        const std::uint64_t ct = g.uint(a, "componentType", where, 0, true);
        const int csize = component_bytes(ct);
        if (csize == 0) fail(where + " componentType " + std::to_string(ct) + " is not a glTF component type");
        if (!a.contains("type") || !a["type"].is_string()) fail(where + " has no type");
        const std::string type = a["type"].get<std::string>();
        const int n = type_components(type);
        if (n == 0) fail(where + " type '" + type + "' is not a glTF type");
        const std::uint64_t count = g.uint(a, "count", where, 0, true);
        if (count > kMaxMeshIndices)
            fail(where + " claims " + std::to_string(count) + " elements, more than the limit of " +
                 std::to_string(kMaxMeshIndices));
        const std::uint64_t elem = std::uint64_t(csize) * std::uint64_t(n);
        if (a.contains("bufferView")) {
            check_in_view(a, where, count, elem);
        } else {
            unbacked += count * elem;
            if (unbacked > unbacked_limit)
                fail(where + ": accessors without a buffer view claim " + std::to_string(unbacked) +
                     " bytes, more than 16 x the file's size");
        }
        if (a.contains("sparse")) {
            const json& s = a["sparse"];
            const std::string sw = where + " sparse";
            if (!s.is_object()) fail(sw + " is not an object");
            const std::uint64_t sc = g.uint(s, "count", sw, 0, true);
            if (sc > count)
                fail(sw + " count " + std::to_string(sc) + " is more than the accessor's " + std::to_string(count));
            if (!s.contains("indices") || !s["indices"].is_object() || !s.contains("values") ||
                !s["values"].is_object())
                fail(sw + " has no indices or values");
            const std::uint64_t ict = g.uint(s["indices"], "componentType", sw + " indices", 0, true);
            const int isize = ict == 5121 ? 1 : ict == 5123 ? 2 : ict == 5125 ? 4 : 0;
            if (isize == 0) fail(sw + " indices componentType " + std::to_string(ict) + " is not an index type");
            check_in_view(s["indices"], sw + " indices", sc, std::uint64_t(isize));
            check_in_view(s["values"], sw + " values", sc, elem);
        }
    }
    const json& meshes = g.array(doc, "meshes", "glTF ");
    for (std::size_t i = 0; i < meshes.size(); ++i) {
        const std::string where = "glTF mesh " + std::to_string(i);
        const json& prims = g.array(meshes[i], "primitives", where + " ");
        for (std::size_t k = 0; k < prims.size(); ++k) {
            const std::string pw = where + " primitive " + std::to_string(k);
            if (!prims[k].is_object() || !prims[k].contains("attributes") || !prims[k]["attributes"].is_object())
                fail(pw + " has no attributes");
            const json& attributes = prims[k]["attributes"];
            if (!attributes.contains("POSITION")) fail(pw + " has no POSITION");
            const std::uint64_t position =
                g.index_value(attributes["POSITION"], pw + " POSITION", accessors.size(), "accessors");
            const std::uint64_t vertices = g.uint(accessors[position], "count", pw, 0);
            // Every attribute holds one element per vertex (glTF 2.0 §3.7.2.1): assimp reads them by POSITION's count.
            for (const auto& [name, v] : attributes.items()) {
                const json& a = accessors[g.index_value(v, pw + " attribute " + name, accessors.size(), "accessors")];
                if (g.uint(a, "count", pw, 0) != vertices)
                    fail(pw + " attribute " + name + " has " + std::to_string(g.uint(a, "count", pw, 0)) +
                         " elements for " + std::to_string(vertices) + " vertices");
            }
            if (g.uint(prims[k], "mode", pw, 4) > 6) fail(pw + " mode is not a glTF primitive mode (0..6)");
            if (!prims[k].contains("indices") || prims[k].contains("extensions")) continue;  // (Draco: its own)
            const std::uint64_t ai = g.index(prims[k], "indices", pw, accessors.size(), "accessors");
            const json& a = accessors[ai];
            const std::uint64_t ct = g.uint(a, "componentType", pw, 0);
            const int size = ct == 5121 ? 1 : ct == 5123 ? 2 : ct == 5125 ? 4 : 0;
            if (size == 0) fail(pw + " indices accessor " + std::to_string(ai) + " is not of an unsigned integer type");
            if (!a.contains("bufferView") || a.contains("sparse")) continue;  // zeros, or sparse: not read here
            const json& v = views[a["bufferView"].get<std::size_t>()];
            const std::string_view buf = buffer_bytes[v["buffer"].get<std::size_t>()];
            if (buf.empty()) continue;
            const std::uint64_t stride = std::max<std::uint64_t>(g.uint(v, "byteStride", pw, 0), std::uint64_t(size));
            const std::uint64_t at = g.uint(v, "byteOffset", pw, 0) + g.uint(a, "byteOffset", pw, 0);
            const std::uint64_t count = g.uint(a, "count", pw, 0);
            for (std::uint64_t i = 0; i < count; ++i) {  // inside the view and the buffer: checked above
                const std::size_t o = std::size_t(at + i * stride);
                std::uint32_t idx = static_cast<unsigned char>(buf[o]);
                if (size >= 2) idx |= std::uint32_t(static_cast<unsigned char>(buf[o + 1])) << 8;
                if (size == 4)
                    idx |= std::uint32_t(static_cast<unsigned char>(buf[o + 2])) << 16 |
                           std::uint32_t(static_cast<unsigned char>(buf[o + 3])) << 24;
                if (idx >= vertices)
                    fail(pw + " index " + std::to_string(i) + " is vertex " + std::to_string(idx) +
                         ", out of range (" + std::to_string(vertices) + " vertices)");
            }
        }
    }
    // Nodes: a forest at most kMaxGltfDepth deep (an explicit stack: this check must not recurse either).
    const json& nodes = g.array(doc, "nodes", "glTF ");
    std::vector<int> parent(nodes.size(), -1);
    for (std::size_t i = 0; i < nodes.size(); ++i) {
        const std::string where = "glTF node " + std::to_string(i);
        if (!nodes[i].is_object()) fail(where + " is not an object");
        if (nodes[i].contains("mesh")) g.index(nodes[i], "mesh", where, meshes.size(), "meshes");
        for (const json& c : g.array(nodes[i], "children", where + " ")) {
            const std::uint64_t k = g.index_value(c, where + " child", nodes.size(), "nodes");
            if (parent[k] >= 0 || k == i)
                fail("glTF node " + std::to_string(k) + " has two parents (nodes " +
                     std::to_string(parent[k] < 0 ? i : std::size_t(parent[k])) + " and " + std::to_string(i) +
                     "): the node graph is not a tree");
            parent[k] = int(i);
        }
        if (nodes[i].contains("matrix")) {
            const json& m = nodes[i]["matrix"];
            if (!m.is_array() || m.size() != 16) fail(where + " matrix is not 16 numbers");
        }
    }
    for (std::size_t i = 0; i < nodes.size(); ++i) {  // depth by walking up: a cycle shows as a path too long
        int d = 0;
        for (int k = int(i); k >= 0; k = parent[std::size_t(k)])
            if (++d > kMaxGltfDepth)
                fail("glTF node " + std::to_string(i) + " is more than " + std::to_string(kMaxGltfDepth) +
                     " levels deep (or in a cycle)");
    }
    for (const json& s : g.array(doc, "scenes", "glTF "))
        for (const json& n : g.array(s, "nodes", "glTF scene "))
            g.index_value(n, "glTF scene node", nodes.size(), "nodes");
}

}  // namespace

void precheck_material_library(const std::string& bytes, const std::string& mesh_name, const std::string& file) {
    check_mtl_statements(bytes, "material library " + file, Fail{mesh_name});
}

void precheck_mesh(const std::string& bytes, const std::string& name, const std::string& ext,
                   const SidecarBytes& sidecar, MeshPrecheckFacts* facts) {
    const Fail fail{name};
    if (bytes.empty()) fail("the file is empty");
    if (ext == ".ply") check_ply(bytes, fail);
    else if (ext == ".obj") {
        check_obj(bytes, fail);
        check_mtl_statements(bytes, "OBJ", fail);  // an OBJ may name itself as its mtllib: assimp then reads it as one
    }
    else if (ext == ".gltf") check_gltf(bytes, false, fail, sidecar, facts);
    else if (ext == ".glb") check_gltf(bytes, true, fail, sidecar, facts);
    else fail("not a mesh file extension (.obj, .ply, .gltf, .glb)");
}

}  // namespace ngi::detail
