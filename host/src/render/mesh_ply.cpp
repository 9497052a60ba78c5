// PLY (ASCII, binary little and big endian) -> MeshFile: ngi's own reader, the only parser of the format.
// The header declares every element's count and the types of its properties, so the bytes the body needs are known
// before it is read: counts are checked against ngi's limits and against the bytes present before anything is
// allocated for them, and every list against the bytes (binary) or values (text) left. Read: one `vertex` element
// (x, y, z; nx, ny, nz; red, green, blue as r/g/b or diffuse_*; u, v as s/t or texture_*) and one `face` element
// (a `vertex_indices` or `vertex_index` list); other elements are walked over. A face of 1 or 2 indices is a point
// or a line (counted, dropped), of 3 or more a polygon.
#include <charconv>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ngi/mesh.hpp"
#include "render/finite.hpp"
#include "render/mesh_source.hpp"

namespace ngi::detail {
namespace {

struct PlyProperty {
    bool list = false;
    int type = 0;        // index into kPlyTypes: the scalar, or the list's items
    int count_type = 0;  // the list's count
    std::string name;
};

struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> props;
};

struct PlyType {
    const char* a;
    const char* b;
    int size;
    bool is_signed, is_float;
    double colour_scale;  // what a colour of this type is divided by (integers: their largest value)
};
constexpr PlyType kPlyTypes[] = {{"", "", 0, false, false, 1.0},
                                 {"char", "int8", 1, true, false, 127.0},
                                 {"uchar", "uint8", 1, false, false, 255.0},
                                 {"short", "int16", 2, true, false, 32767.0},
                                 {"ushort", "uint16", 2, false, false, 65535.0},
                                 {"int", "int32", 4, true, false, 2147483647.0},
                                 {"uint", "uint32", 4, false, false, 4294967295.0},
                                 {"float", "float32", 4, true, true, 1.0},
                                 {"double", "float64", 8, true, true, 1.0}};

int ply_type(std::string_view t) {
    for (int i = 1; i < int(std::size(kPlyTypes)); ++i)
        if (t == kPlyTypes[i].a || t == kPlyTypes[i].b) return i;
    return 0;
}

bool ply_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

std::vector<std::string_view> ply_tokens(std::string_view line) {
    std::vector<std::string_view> t;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && ply_blank(line[i])) ++i;
        const std::size_t s = i;
        while (i < line.size() && !ply_blank(line[i])) ++i;
        if (i > s) t.push_back(line.substr(s, i - s));
    }
    return t;
}

// The body, one value at a time, in either encoding.
class PlyBody {
public:
    enum class Encoding { Ascii, Little, Big };
    PlyBody(const std::string& b, std::size_t at, Encoding enc, const std::string& name)
        : b_(b), p_(at), enc_(enc), name_(name) {}

    // Starts element `i` of `e`: in text, its line (blank lines skipped).
    void begin(const PlyElement& e, std::uint64_t i) {
        where_ = "PLY " + e.name + " " + std::to_string(i);
        if (enc_ != Encoding::Ascii) return;
        line_.clear();
        next_ = 0;
        while (line_.empty()) {
            if (p_ >= b_.size())
                mesh_fail(name_, "PLY body ends at " + e.name + " " + std::to_string(i) + " of " +
                                     std::to_string(e.count) + " (truncated)");
            const std::size_t nl = b_.find('\n', p_);
            line_ = ply_tokens(std::string_view(b_.data() + p_, (nl == std::string::npos ? b_.size() : nl) - p_));
            p_ = nl == std::string::npos ? b_.size() : nl + 1;
        }
    }
    // Ends an element: in text, every value on its line must have been read.
    void end() {
        if (enc_ == Encoding::Ascii && next_ != line_.size())
            mesh_fail(name_, where_ + ": " + std::to_string(line_.size()) + " values on its line, its properties take " +
                                 std::to_string(next_));
    }
    // Values left for a list of items of `type` (binary: bytes left / item size; text: values left on the line).
    std::uint64_t room(int type) const {
        return enc_ == Encoding::Ascii ? line_.size() - next_ : (b_.size() - p_) / std::uint64_t(kPlyTypes[type].size);
    }
    double value(int type) {
        const PlyType& t = kPlyTypes[type];
        if (enc_ == Encoding::Ascii) {
            if (next_ >= line_.size())
                mesh_fail(name_, where_ + ": its line ends before its properties (" + std::to_string(line_.size()) +
                                     " values)");
            const std::string_view tok = line_[next_++];
            double v = 0;
            if (t.is_float) {
                const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), v);
                if (r.ec == std::errc::invalid_argument || r.ptr != tok.data() + tok.size())
                    mesh_fail(name_, where_ + ": '" + mesh_printable(std::string(tok)) + "' is not a number");
                return double(t.size == 4 ? double(float(v)) : v);
            }
            std::int64_t n = 0;
            const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), n);
            const double lo = t.is_signed ? -t.colour_scale - 1.0 : 0.0;
            if (r.ec != std::errc() || r.ptr != tok.data() + tok.size() || double(n) < lo || double(n) > t.colour_scale)
                mesh_fail(name_, where_ + ": '" + mesh_printable(std::string(tok)) + "' is not a " + t.a);
            return double(n);
        }
        if (std::uint64_t(t.size) > b_.size() - p_)
            mesh_fail(name_, where_ + ": the body ends inside it (truncated)");
        unsigned char c[8];
        std::memcpy(c, b_.data() + p_, std::size_t(t.size));
        p_ += std::size_t(t.size);
        if (enc_ == Encoding::Big)
            for (int k = 0; k < t.size / 2; ++k) std::swap(c[k], c[t.size - 1 - k]);
        switch (type) {
            case 1: return double(std::int8_t(c[0]));
            case 2: return double(c[0]);
            case 3: { std::int16_t v; std::memcpy(&v, c, 2); return v; }
            case 4: { std::uint16_t v; std::memcpy(&v, c, 2); return v; }
            case 5: { std::int32_t v; std::memcpy(&v, c, 4); return v; }
            case 6: { std::uint32_t v; std::memcpy(&v, c, 4); return v; }
            case 7: { float v; std::memcpy(&v, c, 4); return v; }
            default: { double v; std::memcpy(&v, c, 8); return v; }
        }
    }
    const std::string& where() const { return where_; }

private:
    const std::string& b_;
    std::size_t p_;
    Encoding enc_;
    const std::string& name_;
    std::string where_;
    std::vector<std::string_view> line_;
    std::size_t next_ = 0;
};

// Which vertex value a property holds: 0-2 position, 3-5 normal, 6-8 colour, 9-10 texture coordinate, -1 none.
int ply_vertex_slot(const std::string& n) {
    static const char* const names[][4] = {
        {"x", nullptr, nullptr, nullptr},      {"y", nullptr, nullptr, nullptr},
        {"z", nullptr, nullptr, nullptr},      {"nx", nullptr, nullptr, nullptr},
        {"ny", nullptr, nullptr, nullptr},     {"nz", nullptr, nullptr, nullptr},
        {"red", "r", "diffuse_red", nullptr},  {"green", "g", "diffuse_green", nullptr},
        {"blue", "b", "diffuse_blue", nullptr}, {"u", "s", "texture_u", "texture_s"},
        {"v", "t", "texture_v", "texture_t"}};
    for (int s = 0; s < 11; ++s)
        for (const char* a : names[s])
            if (a && n == a) return s;
    return -1;
}

}  // namespace

MeshFile read_ply(const std::string& b, const std::string& name) {
    auto fail = [&](const std::string& what) { mesh_fail(name, what); };
    // The header: text lines up to "end_header". 64 KiB is far more than any real header (a few hundred bytes).
    constexpr std::size_t kMaxHeader = 64 * 1024;
    std::vector<PlyElement> elements;
    PlyBody::Encoding enc = PlyBody::Encoding::Ascii;
    bool have_format = false;
    std::size_t pos = 0, body = std::string::npos;
    for (int line_no = 1; pos < b.size() && body == std::string::npos; ++line_no) {
        if (pos > kMaxHeader) fail("PLY header longer than 64 KiB (no end_header)");
        const std::size_t nl = b.find('\n', pos);
        const std::string_view line(b.data() + pos, (nl == std::string::npos ? b.size() : nl) - pos);
        pos = nl == std::string::npos ? b.size() : nl + 1;
        const std::string at = " on header line " + std::to_string(line_no);
        for (char ch : line)
            if ((static_cast<unsigned char>(ch) < 0x20 && ch != '\t' && ch != '\r') || ch == 0x7f)
                fail("PLY header line " + std::to_string(line_no) + ": control character (not a text header)");
        const auto t = ply_tokens(line);
        if (line_no == 1) {
            if (t.size() != 1 || (t[0] != "ply" && t[0] != "PLY")) fail("not a PLY file (no \"ply\" first line)");
        } else if (t.empty() || t[0] == "comment" || t[0] == "obj_info") {
        } else if (t[0] == "end_header") {
            body = pos;
        } else if (t[0] == "format") {
            if (t.size() < 2) fail("PLY header: bad format line");
            if (t[1] == "ascii") enc = PlyBody::Encoding::Ascii;
            else if (t[1] == "binary_little_endian") enc = PlyBody::Encoding::Little;
            else if (t[1] == "binary_big_endian") enc = PlyBody::Encoding::Big;
            else fail("PLY header: unknown format '" + mesh_printable(std::string(t[1])) + "'");
            have_format = true;
        } else if (t[0] == "element") {
            std::uint64_t n = 0;
            if (t.size() != 3) fail("PLY header: bad element line" + at);
            const auto r = std::from_chars(t[2].data(), t[2].data() + t[2].size(), n);
            if (r.ec != std::errc() || r.ptr != t[2].data() + t[2].size())
                fail("PLY header: element '" + mesh_printable(std::string(t[1])) + "' count '" +
                     mesh_printable(std::string(t[2])) + "' is not a non-negative integer");
            // Triangle strips would need their own reading (-1 restarts, alternating winding); real PLY files
            // (scans, exporters) write faces.
            if (t[1] == "tristrips") fail("PLY tristrips elements are not supported (write faces)");
            if (t[1] == "vertex" || t[1] == "face")
                for (const auto& e : elements)
                    if (e.name == t[1])
                        fail("PLY header: a second '" + std::string(t[1]) + "' element" + at + " (one of each is supported)");
            elements.push_back({std::string(t[1]), n, {}});
            // Every element is a vertex, a face or something else the same size or larger: the triangle limit bounds
            // them all (2^24 is both limits).
            const std::uint64_t limit = elements.back().name == "vertex" ? kMaxMeshVertices : kMaxMeshTriangles;
            if (n > limit)
                fail("PLY header claims " + std::to_string(n) + " elements '" + mesh_printable(elements.back().name) +
                     "', more than the limit of " + std::to_string(limit));
        } else if (t[0] == "property") {
            if (elements.empty()) fail("PLY header: property before any element");
            PlyProperty p;
            if (t.size() == 5 && t[1] == "list") {
                p.list = true;
                p.count_type = ply_type(t[2]);
                p.type = ply_type(t[3]);
                p.name = std::string(t[4]);
                if (p.count_type == 0 || p.type == 0 || kPlyTypes[p.count_type].is_float)
                    fail("PLY header: bad list types of property '" + mesh_printable(p.name) + "'");
            } else if (t.size() == 3) {
                p.type = ply_type(t[1]);
                p.name = std::string(t[2]);
                if (p.type == 0)
                    fail("PLY header: unknown type '" + mesh_printable(std::string(t[1])) + "' of property '" +
                         mesh_printable(p.name) + "'");
            } else {
                fail("PLY header: bad property line" + at);
            }
            elements.back().props.push_back(p);
        } else {
            fail("PLY header: unknown keyword '" + mesh_printable(std::string(t[0])) + "'" + at);
        }
    }
    if (body == std::string::npos) fail("PLY header has no end_header (truncated)");
    if (!have_format) fail("PLY header has no format line");
    for (const auto& e : elements)
        if (e.count > 0 && e.props.empty()) fail("PLY element '" + mesh_printable(e.name) + "' has no properties");
    // A triangle mesh: vertices with x, y, z and faces with a vertex-index list (a point cloud has no triangle).
    const PlyElement* vertex_element = nullptr;
    const PlyElement* face_element = nullptr;
    for (const auto& e : elements) {
        if (e.name == "vertex") vertex_element = &e;
        if (e.name == "face") face_element = &e;
    }
    for (const char* c : {"x", "y", "z"}) {
        bool found = false;
        for (const auto& p : vertex_element ? vertex_element->props : std::vector<PlyProperty>{})
            found = found || (p.name == c && !p.list);
        if (!found) fail(std::string("PLY has no vertex element with a scalar property ") + c);
    }
    int index_list = -1;
    for (std::size_t k = 0; face_element && k < face_element->props.size(); ++k)
        if (face_element->props[k].list &&
            (face_element->props[k].name == "vertex_indices" || face_element->props[k].name == "vertex_index"))
            index_list = int(k);
    if (index_list < 0) fail("PLY has no face element with a vertex_indices list (a point cloud has no triangles)");
    if (kPlyTypes[face_element->props[std::size_t(index_list)].type].is_float)
        fail("PLY face list '" + face_element->props[std::size_t(index_list)].name + "' holds floats, not vertex indices");

    // The least the body can hold: each scalar once, each list's count (binary), or one character and a separator
    // per value (text). Checked first, so a short file claiming millions of elements is refused without a walk.
    const std::uint64_t left = b.size() - body;
    std::uint64_t least = 0;
    for (const auto& e : elements) {
        std::uint64_t per = 0;
        for (const auto& p : e.props)
            per += enc == PlyBody::Encoding::Ascii ? 2 : std::uint64_t(kPlyTypes[p.list ? p.count_type : p.type].size);
        least += per * e.count;  // <= 2^24 elements x (8 bytes x properties): no overflow for any header below 64 KiB
    }
    if (least > left + 1)
        fail("PLY body needs at least " + std::to_string(least) + " bytes for the elements its header declares, the "
             "file has " + std::to_string(left) + " (truncated, or counts that are not true)");

    MeshFile out;
    out.format = MeshFormat::Ply;
    out.parts.emplace_back();
    out.instances.push_back({0, glm::mat4(1.0f)});
    MeshPart& part = out.parts.back();
    bool has[4] = {false, false, false, false};  // position, normal, colour, texture coordinate
    for (const auto& p : vertex_element->props)
        if (!p.list && ply_vertex_slot(p.name) >= 0) has[ply_vertex_slot(p.name) / 3] = true;
    const std::size_t nv = std::size_t(vertex_element->count);
    part.positions.resize(nv);
    if (has[1]) part.normals.resize(nv, glm::vec3(0.0f));
    if (has[2]) part.colours.resize(nv, glm::vec3(0.0f));
    if (has[3]) part.texcoords.resize(nv, glm::vec2(0.0f));

    PlyBody in(b, body, enc, name);
    std::uint64_t triangles = 0;
    for (const auto& e : elements) {
        const bool is_vertex = &e == vertex_element, is_face = &e == face_element;
        for (std::uint64_t i = 0; i < e.count; ++i) {
            in.begin(e, i);
            for (std::size_t k = 0; k < e.props.size(); ++k) {
                const PlyProperty& p = e.props[k];
                if (!p.list) {
                    const double v = in.value(p.type);
                    const int slot = is_vertex ? ply_vertex_slot(p.name) : -1;
                    if (slot >= 0 && slot < 6) (slot < 3 ? part.positions : part.normals)[i][slot % 3] = float(v);
                    else if (slot >= 6 && slot < 9) part.colours[i][slot - 6] = float(v / kPlyTypes[p.type].colour_scale);
                    else if (slot >= 9) part.texcoords[i][slot - 9] = float(v);
                    continue;
                }
                const double count = in.value(p.count_type);
                if (count < 0 || count > double(in.room(p.type)))
                    fail(in.where() + ": list '" + mesh_printable(p.name) + "' claims " +
                         (count < 0 ? mesh_number(count) : std::to_string(std::uint64_t(count))) +
                         " items, more than the " + std::to_string(in.room(p.type)) + " values left hold");
                const auto n = std::uint32_t(count);
                if (!is_face || int(k) != index_list) {
                    for (std::uint32_t j = 0; j < n; ++j) in.value(p.type);
                    continue;
                }
                if (n == 0) fail(in.where() + " has no vertex index");
                if (n >= 3) triangles += n - 2;
                if (triangles > kMaxMeshTriangles)
                    fail(in.where() + ": the faces so far make more than " + std::to_string(kMaxMeshTriangles) +
                         " triangles");
                for (std::uint32_t j = 0; j < n; ++j) {
                    const double v = in.value(p.type);
                    if (!(v >= 0 && v < double(nv)))
                        fail(in.where() + ": vertex index " + mesh_number(v) + " is out of range (" +
                             std::to_string(nv) + " vertices)");
                    if (n >= 3) part.corners.push_back(std::uint32_t(v));
                }
                if (n >= 3) part.sizes.push_back(n);
                else part.dropped_primitives += 1;
            }
            in.end();
            if (!is_vertex) continue;
            if (!finite(part.positions[i])) fail(in.where() + ": position is not finite");
            if (has[1] && !finite(part.normals[i])) fail(in.where() + ": normal is not finite");
            if (has[2] && !finite(part.colours[i])) fail(in.where() + ": colour is not finite");
        }
    }
    return out;
}

}  // namespace ngi::detail
