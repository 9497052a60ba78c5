// MagicaVoxel .vox reader (https://github.com/ephtracy/voxel-model, format and its scene-graph extension).
// The file is a RIFF-like tree: "VOX " version, then MAIN whose children are SIZE/XYZI model pairs, RGBA, MATL,
// the scene graph (nTRN/nGRP/nSHP) and chunks we do not use; every chunk is id, content bytes, children bytes.
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <stdexcept>

#include "base/file_util.hpp"
#include "ngi/error.hpp"
#include "ngi/scene.hpp"

namespace ngi {
namespace {

constexpr int kMaxModelAxis = 256;  // MagicaVoxel's own limit per model
constexpr std::size_t kMaxModels = 4096;

class Reader {
public:
    Reader(const std::string& path, const std::string& bytes, std::size_t begin, std::size_t end)
        : path_(&path), b_(&bytes), pos_(begin), end_(end) {}
    [[noreturn]] void fail(const std::string& what) const {
        throw InputError("read " + *path_ + ": " + what + " (byte " + std::to_string(pos_) + ")");
    }
    std::size_t pos() const { return pos_; }
    std::size_t left() const { return end_ - pos_; }
    void need(std::size_t n, const char* what) const {
        if (left() < n) fail(std::string("truncated ") + what);
    }
    std::int32_t i32(const char* what) {
        need(4, what);
        const auto* p = reinterpret_cast<const unsigned char*>(b_->data() + pos_);
        pos_ += 4;
        return std::int32_t(std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 |
                            std::uint32_t(p[3]) << 24);
    }
    std::string bytes(std::size_t n, const char* what) {
        need(n, what);
        std::string s = b_->substr(pos_, n);
        pos_ += n;
        return s;
    }
    std::string str(const char* what) {
        const std::int32_t n = i32(what);
        if (n < 0) fail(std::string("negative string length in ") + what);
        return bytes(std::size_t(n), what);
    }
    std::map<std::string, std::string> dict(const char* what) {
        const std::int32_t n = i32(what);
        if (n < 0 || std::size_t(n) > left() / 8) fail(std::string("bad dictionary size in ") + what);
        std::map<std::string, std::string> d;
        for (int i = 0; i < n; ++i) {
            std::string k = str(what);
            d[k] = str(what);
        }
        return d;
    }

private:
    const std::string* path_;
    const std::string* b_;
    std::size_t pos_, end_;
};

using L3 = glm::vec<3, std::int64_t>;  // positions while walking the scene graph

[[noreturn]] void input_error(const std::string& path, const std::string& what) {
    throw InputError("read " + path + ": " + what);
}

struct VoxModel {
    glm::ivec3 size{0};
    std::vector<std::array<std::uint8_t, 4>> voxels;  // x, y, z, colour index
};

// A MagicaVoxel rotation: a signed permutation matrix, rows packed in one byte.
using IMat = std::array<glm::ivec3, 3>;  // rows
IMat identity() { return {glm::ivec3(1, 0, 0), glm::ivec3(0, 1, 0), glm::ivec3(0, 0, 1)}; }
int idot(glm::ivec3 a, glm::ivec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
glm::ivec3 mul(const IMat& m, glm::ivec3 v) { return {idot(m[0], v), idot(m[1], v), idot(m[2], v)}; }
IMat mul(const IMat& a, const IMat& b) {
    IMat r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
    return r;
}

struct Node {
    enum Kind { Transform, Group, Shape } kind;
    IMat rot = identity();
    L3 t{0};                    // nTRN translation, within +-kMaxVoxCoord
    std::vector<int> children;  // node ids (transform: one; group: many) or model ids (shape)
};

float srgb8_to_linear(std::uint8_t v) {
    const float c = float(v) / 255.0f;
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

// The default palette (used when a file has no RGBA chunk), generated from its structure: index 0 unused;
// 1..215 the 6x6x6 colour cube (r outer, g, b inner, each ff cc 99 66 33 00, without black); then ten-step ramps
// (ee dd bb aa 88 77 55 44 22 11) of red, green, blue and grey.
std::array<std::array<std::uint8_t, 3>, 256> default_palette() {
    std::array<std::array<std::uint8_t, 3>, 256> p{};
    int i = 1;
    for (int r = 5; r >= 0; --r)
        for (int g = 5; g >= 0; --g)
            for (int b = 5; b >= 0; --b)
                if (r || g || b) p[i++] = {std::uint8_t(r * 0x33), std::uint8_t(g * 0x33), std::uint8_t(b * 0x33)};
    const std::uint8_t ramp[10] = {0xee, 0xdd, 0xbb, 0xaa, 0x88, 0x77, 0x55, 0x44, 0x22, 0x11};
    for (int c = 0; c < 4; ++c)
        for (std::uint8_t v : ramp)
            p[i++] = {std::uint8_t(c == 0 || c == 3 ? v : 0), std::uint8_t(c == 1 || c == 3 ? v : 0),
                      std::uint8_t(c == 2 || c == 3 ? v : 0)};
    return p;
}

IMat decode_rotation(const Reader& rd, int bits) {
    const int i0 = bits & 3, i1 = (bits >> 2) & 3;
    if (i0 > 2 || i1 > 2 || i0 == i1) rd.fail("invalid rotation " + std::to_string(bits) + " in nTRN");
    const int i2 = 3 - i0 - i1;
    IMat m{glm::ivec3(0), glm::ivec3(0), glm::ivec3(0)};
    m[0][i0] = (bits & 16) ? -1 : 1;
    m[1][i1] = (bits & 32) ? -1 : 1;
    m[2][i2] = (bits & 64) ? -1 : 1;
    return m;
}

int parse_vox_int(const Reader& rd, const std::string& s, const char* what) {
    try {
        std::size_t used = 0;
        const int v = std::stoi(s, &used);
        if (used != s.size()) throw std::invalid_argument(s);
        return v;
    } catch (const std::exception&) {
        rd.fail(std::string("bad number '") + s + "' in " + what);
    }
}

// nTRN "_t": three integers separated by spaces, each within +-kMaxVoxCoord (so that sums over kMaxVoxDepth
// levels, doubled for half-voxel centres, stay far from int overflow).
L3 parse_translation(const Reader& rd, const std::string& s) {
    L3 t(0);
    const char* p = s.data();
    const char* const end = s.data() + s.size();
    for (int k = 0; k < 3; ++k) {
        while (p < end && *p == ' ') ++p;
        if (end - p > 1 && *p == '+' && p[1] >= '0' && p[1] <= '9') ++p;  // from_chars takes no '+'
        std::int64_t v = 0;
        const auto r = std::from_chars(p, end, v);
        if (r.ec == std::errc::result_out_of_range || (r.ec == std::errc() && (v > kMaxVoxCoord || v < -kMaxVoxCoord)))
            rd.fail("translation '" + s + "' in nTRN is beyond +-" + std::to_string(kMaxVoxCoord) + " blocks");
        if (r.ec != std::errc()) rd.fail("bad translation '" + s + "' in nTRN");
        t[k] = v;
        p = r.ptr;
    }
    while (p < end && *p == ' ') ++p;
    if (p != end) rd.fail("bad translation '" + s + "' in nTRN");
    return t;
}

// A MATL number (MagicaVoxel writes them with printf %g); must be finite.
float parse_float(const Reader& rd, const std::string& s, const char* what) {
    char* stop = nullptr;
    const float v = std::strtof(s.c_str(), &stop);
    if (s.empty() || stop != s.c_str() + s.size() || !std::isfinite(v))
        rd.fail(std::string("bad number '") + s + "' in " + what);
    return v;
}

}  // namespace

VoxelScene load_vox(const std::string& path) {
    // ngi's file rule (detail::read_file): a FIFO named x.vox once blocked this reader's std::ifstream in open()
    // forever; read_file refuses anything but a regular file before opening it, and caps the size.
    return parse_vox(detail::read_file(path, "read .vox scene", kMaxVoxFileBytes), path);
}

VoxelScene parse_vox(const std::string& b, const std::string& path) {
    Reader rd(path, b, 0, b.size());
    if (rd.left() < 8 || b.compare(0, 4, "VOX ") != 0) rd.fail("not a MagicaVoxel file (no \"VOX \" header)");
    rd.bytes(4, "header");
    const std::int32_t version = rd.i32("header");
    if (version < 150 || version > 200) rd.fail("unsupported .vox version " + std::to_string(version));

    // Reads a chunk header; checks the id is printable and both sizes fit inside `limit`.
    struct Chunk { std::string id; std::size_t content, children, begin; };
    auto chunk = [&](Reader& r) {
        Chunk c;
        c.id = r.bytes(4, "chunk header");
        for (unsigned char ch : c.id)
            if (ch < 0x20 || ch > 0x7e) r.fail("malformed chunk structure: chunk id is not text");
        const std::int32_t n = r.i32("chunk header"), m = r.i32("chunk header");
        if (n < 0 || m < 0) r.fail("malformed chunk structure: negative size in chunk '" + c.id + "'");
        c.content = std::size_t(n);
        c.children = std::size_t(m);
        c.begin = r.pos();
        if (c.content > r.left() || c.children > r.left() - c.content)
            r.fail("truncated chunk '" + c.id + "' (" + std::to_string(c.content + c.children) + " bytes declared, " +
                   std::to_string(r.left()) + " left)");
        return c;
    };

    const Chunk main = chunk(rd);
    if (main.id != "MAIN") rd.fail("malformed chunk structure: expected MAIN, found '" + main.id + "'");
    std::vector<VoxModel> models;
    std::array<std::array<std::uint8_t, 3>, 256> colours = default_palette();
    std::map<int, glm::vec3> emit;  // MATL emission per colour index
    std::map<int, Node> nodes;
    Reader kids(path, b, main.begin + main.content, main.begin + main.content + main.children);
    while (kids.left() > 0) {
        const Chunk c = chunk(kids);
        Reader r(path, b, c.begin, c.begin + c.content);
        if (c.id == "SIZE") {
            glm::ivec3 s;
            s.x = r.i32("SIZE");
            s.y = r.i32("SIZE");
            s.z = r.i32("SIZE");
            if (glm::any(glm::lessThan(s, glm::ivec3(1))) || glm::any(glm::greaterThan(s, glm::ivec3(kMaxModelAxis))))
                r.fail("model size " + std::to_string(s.x) + " x " + std::to_string(s.y) + " x " + std::to_string(s.z) +
                       " is outside 1.." + std::to_string(kMaxModelAxis) + " per axis");
            if (models.size() >= kMaxModels) r.fail("more than " + std::to_string(kMaxModels) + " models");
            models.push_back({s, {}});
        } else if (c.id == "XYZI") {
            if (models.empty() || !models.back().voxels.empty()) r.fail("malformed chunk structure: XYZI without SIZE");
            VoxModel& m = models.back();
            const std::int32_t n = r.i32("XYZI");
            if (n < 0 || std::size_t(n) > r.left() / 4) r.fail("truncated XYZI (" + std::to_string(n) + " voxels declared)");
            m.voxels.resize(std::size_t(n));
            for (auto& v : m.voxels) {
                const std::string e = r.bytes(4, "XYZI");
                for (int k = 0; k < 4; ++k) v[k] = std::uint8_t(e[k]);
                if (v[0] >= m.size.x || v[1] >= m.size.y || v[2] >= m.size.z)
                    r.fail("voxel (" + std::to_string(v[0]) + ", " + std::to_string(v[1]) + ", " + std::to_string(v[2]) +
                           ") outside its model");
            }
        } else if (c.id == "RGBA") {
            for (int i = 1; i <= 255; ++i) {  // entry i-1 of the chunk is colour index i
                const std::string e = r.bytes(4, "RGBA");
                colours[i] = {std::uint8_t(e[0]), std::uint8_t(e[1]), std::uint8_t(e[2])};
            }
        } else if (c.id == "MATL") {
            const int id = r.i32("MATL");
            auto d = r.dict("MATL");
            if (d["_type"] == "_emit" && id >= 1 && id <= 255) {
                const float e = d.count("_emit") ? parse_float(r, d["_emit"], "MATL _emit") : 1.0f;
                const float flux = d.count("_flux") ? parse_float(r, d["_flux"], "MATL _flux") : 0.0f;
                // In double, then bounded: a finite _emit of 3e38 (or 1e37 with _flux 4) overflowed float to Inf
                // here, and an Inf light renders black (ngi/material.hpp, kMaxEmission).
                const double scaled = std::max(0.0, double(e)) * 4.0 * std::exp2(double(std::clamp(flux, 0.0f, 4.0f)));
                if (!(scaled <= double(kMaxEmission)))
                    r.fail("MATL of colour index " + std::to_string(id) + ": emission _emit " + d["_emit"] + " x 4 x 2^" +
                           "_flux (" + (d.count("_flux") ? d["_flux"] : std::string("0")) + ") = " +
                           std::to_string(scaled) + " exceeds the bound of " + std::to_string(int(kMaxEmission)));
                emit[id] = glm::vec3(std::max(0.0f, e) * 4.0f * std::exp2(std::clamp(flux, 0.0f, 4.0f)));  // as before
            }
        } else if (c.id == "nTRN" || c.id == "nGRP" || c.id == "nSHP") {
            const int id = r.i32(c.id.c_str());
            r.dict(c.id.c_str());
            Node node;
            if (c.id == "nTRN") {
                node.kind = Node::Transform;
                node.children.push_back(r.i32("nTRN"));
                r.i32("nTRN");  // reserved
                r.i32("nTRN");  // layer
                const int frames = r.i32("nTRN");
                if (frames < 1) r.fail("nTRN without frames");
                // Only frame 0 is read, but the count must be one the chunk can hold: each frame is a dictionary
                // of at least 4 bytes (its entry count). INT_MAX frames in a 60-byte chunk is a broken file.
                if (std::size_t(frames) > r.left() / 4)
                    r.fail("nTRN declares " + std::to_string(frames) + " frames, more than its " +
                           std::to_string(r.left()) + " bytes can hold");
                auto f = r.dict("nTRN");  // frame 0; animation frames are ignored
                if (f.count("_r")) node.rot = decode_rotation(r, parse_vox_int(r, f["_r"], "nTRN _r"));
                if (f.count("_t")) node.t = parse_translation(r, f["_t"]);
            } else if (c.id == "nGRP") {
                node.kind = Node::Group;
                const int n = r.i32("nGRP");
                if (n < 0 || std::size_t(n) > r.left() / 4) r.fail("bad child count in nGRP");
                for (int i = 0; i < n; ++i) node.children.push_back(r.i32("nGRP"));
            } else {
                node.kind = Node::Shape;
                const int n = r.i32("nSHP");
                if (n < 0 || std::size_t(n) > r.left() / 8) r.fail("bad model count in nSHP");
                for (int i = 0; i < n; ++i) {
                    node.children.push_back(r.i32("nSHP"));
                    r.dict("nSHP");
                }
            }
            if (!nodes.emplace(id, std::move(node)).second) r.fail("duplicate scene-graph node " + std::to_string(id));
        }
        // Every other chunk (PACK, LAYR, rOBJ, rCAM, NOTE, IMAP, MATT, ...) is skipped by its declared sizes.
        kids = Reader(path, b, c.begin + c.content + c.children, main.begin + main.content + main.children);
    }
    if (models.empty()) throw InputError("read " + path + ": no model (SIZE/XYZI chunks) in the file");

    // Model instances in MagicaVoxel space (z up): each voxel centre goes to rot * (v + 0.5 - size / 2) + t.
    // The scene graph is a DAG at best (a group may list a subtree twice, nodes may be shared), so the walk is
    // bounded, not just cycle-checked: kMaxVoxDepth nodes per path (an explicit stack, never the call stack),
    // kMaxVoxNodeVisits visits in all, kMaxVoxInstances instances, kMaxVoxPlaced voxels, |t| <= kMaxVoxCoord.
    auto fail = [&](const std::string& what) { input_error(path, what); };
    struct Instance { int model; IMat rot; glm::ivec3 t; };
    std::vector<Instance> instances;
    std::size_t placed = 0;  // voxels the instances place, summed
    auto add_instance = [&](int m, const IMat& rot, L3 t) {
        if (m < 0 || std::size_t(m) >= models.size()) fail("scene graph refers to missing model " + std::to_string(m));
        if (instances.size() >= kMaxVoxInstances)
            fail("more than " + std::to_string(kMaxVoxInstances) + " model instances in the scene graph");
        placed += models[std::size_t(m)].voxels.size();  // <= file size per model: no overflow before the check
        if (placed > kMaxVoxPlaced)
            fail("more than " + std::to_string(kMaxVoxPlaced) + " voxels placed by the scene graph");
        instances.push_back({m, rot, glm::ivec3(t)});  // |t| <= kMaxVoxCoord: fits
    };
    if (!nodes.empty()) {
        // Node ids -> dense indices, resolved once per reference: a visit is then O(1), however often the file makes
        // the walk come back to a node. A missing child is an error only if the walk reaches it.
        constexpr std::size_t kMissing = SIZE_MAX;
        std::vector<const Node*> graph;
        std::vector<int> ids;
        std::map<int, std::size_t> index;
        for (const auto& [id, n] : nodes) {
            index[id] = graph.size();
            graph.push_back(&n);
            ids.push_back(id);
        }
        std::vector<std::vector<std::size_t>> kids(graph.size());  // parallel to Node::children (not for shapes)
        for (std::size_t i = 0; i < graph.size(); ++i)
            if (graph[i]->kind != Node::Shape)
                for (int c : graph[i]->children) {
                    const auto it = index.find(c);
                    kids[i].push_back(it == index.end() ? kMissing : it->second);
                }
        struct Frame { std::size_t node; IMat rot; L3 t; std::size_t next; };  // next: the next child to visit
        std::vector<Frame> stack;
        std::vector<char> on_path(graph.size(), 0);
        std::size_t visits = 0;
        auto enter = [&](std::size_t node, int id, const IMat& rot, L3 t) {
            if (node == kMissing) fail("scene graph refers to missing node " + std::to_string(id));
            if (on_path[node]) fail("scene graph has a cycle at node " + std::to_string(id));
            if (stack.size() >= std::size_t(kMaxVoxDepth))
                fail("scene graph deeper than " + std::to_string(kMaxVoxDepth) + " levels");
            if (++visits > kMaxVoxNodeVisits)
                fail("scene graph expands to more than " + std::to_string(kMaxVoxNodeVisits) +
                     " node visits (groups listing children repeatedly?)");
            on_path[node] = 1;
            stack.push_back({node, rot, t, 0});
        };
        const auto root = index.find(0);
        enter(root == index.end() ? kMissing : root->second, 0, identity(), L3(0));
        while (!stack.empty()) {
            Frame& f = stack.back();
            const Node& n = *graph[f.node];
            if (n.kind == Node::Shape) {
                for (int m : n.children) add_instance(m, f.rot, f.t);
            } else if (f.next < n.children.size()) {
                const std::size_t k = f.next++;
                const int child = n.children[k];
                IMat rot = f.rot;
                L3 t = f.t;
                if (n.kind == Node::Transform) {
                    // Rotation entries are 0 / +-1: rot * n.t keeps |n.t|, the sum stays within +-2^21 until checked.
                    const IMat& r = f.rot;
                    for (int i = 0; i < 3; ++i) t[i] += r[i][0] * n.t.x + r[i][1] * n.t.y + r[i][2] * n.t.z;
                    if (glm::any(glm::greaterThan(glm::abs(t), L3(kMaxVoxCoord))))
                        fail("scene graph places node " + std::to_string(child) + " at (" + std::to_string(t.x) + ", " +
                             std::to_string(t.y) + ", " + std::to_string(t.z) + "), beyond +-" +
                             std::to_string(kMaxVoxCoord) + " blocks");
                    rot = mul(f.rot, n.rot);
                }
                enter(kids[f.node][k], child, rot, t);  // may reallocate the stack: `f` is not used after this
                continue;
            }
            on_path[f.node] = 0;
            stack.pop_back();
        }
    } else {
        for (std::size_t m = 0; m < models.size(); ++m) add_instance(int(m), identity(), L3(0));
    }

    // World cell of a voxel: floor of its centre. Twice the centre, 2 rot v + rot (1 - size) + 2 t, is integral
    // (half-voxel offsets of even sizes) and 2 rot v is even, so cell = rot v + floor((rot (1 - size) + 2 t) / 2):
    // one offset per instance. Up to kMaxVoxPlaced voxels go through the loops below, so they stay lean: the
    // bounding box comes from each model's box (a signed permutation maps a box to a box), the grid index is a
    // linear function of v per instance.
    auto floor_half = [](int a) { return a >= 0 ? a / 2 : -((1 - a) / 2); };  // floor(a / 2)
    auto offset = [&](const Instance& in) {
        const glm::ivec3 k = mul(in.rot, 1 - models[std::size_t(in.model)].size) + 2 * in.t;
        return glm::ivec3(floor_half(k.x), floor_half(k.y), floor_half(k.z));
    };
    struct Box { glm::ivec3 lo{INT32_MAX}, hi{INT32_MIN}; bool solid = false; };  // of voxels with a colour
    std::vector<Box> boxes(models.size());
    for (std::size_t m = 0; m < models.size(); ++m)
        for (const auto& v : models[m].voxels)
            if (v[3] != 0) {
                const glm::ivec3 c(v[0], v[1], v[2]);
                boxes[m] = {glm::min(boxes[m].lo, c), glm::max(boxes[m].hi, c), true};
            }
    glm::ivec3 lo(INT32_MAX), hi(INT32_MIN);
    for (const auto& in : instances) {
        const Box& bx = boxes[std::size_t(in.model)];
        if (!bx.solid) continue;
        const glm::ivec3 o = offset(in), a = mul(in.rot, bx.lo) + o, c = mul(in.rot, bx.hi) + o;
        lo = glm::min(lo, glm::min(a, c));
        hi = glm::max(hi, glm::max(a, c));
    }
    if (lo.x > hi.x) throw InputError("read " + path + ": the file has no voxels");
    // |lo|, |hi| <= kMaxVoxCoord + 256, so the extent fits an int; the product is taken in 64 bits.
    const glm::ivec3 ext = hi - lo + 1;  // MagicaVoxel axes
    if (glm::any(glm::greaterThan(ext, glm::ivec3(kMaxVoxAxis))) ||  // checked first: then the product fits
        std::int64_t(ext.x) * ext.y * ext.z > std::int64_t(kMaxVoxBlocks))
        throw InputError("read " + path + ": scene of " + std::to_string(ext.x) + " x " + std::to_string(ext.y) + " x " +
                         std::to_string(ext.z) + " blocks exceeds the budget of " + std::to_string(kMaxVoxBlocks) +
                         " blocks, " + std::to_string(kMaxVoxAxis) + " per axis");

    // (x, y, z)_vox -> (x, z, -y): z-up to y-up, a proper rotation. With c = cell - lo, our block is
    // (c.x, c.z, ext.y - 1 - c.y), index c.x + X c.z + X Y (ext.y - 1 - c.y) for our X = ext.x, Y = ext.z.
    VoxelScene s({ext.x, ext.z, ext.y}, path);
    const std::int64_t X = ext.x, XY = std::int64_t(ext.x) * ext.z;
    const L3 w(1, -XY, X);  // index weights of c.x, c.y, c.z
    const std::int64_t base = XY * (ext.y - 1);
    const std::int64_t blocks = std::int64_t(s.voxels.size());
    std::array<int, 256> material{};  // colour index -> palette index, 0 = not yet added
    for (const auto& in : instances) {
        const glm::ivec3 o = offset(in) - lo;
        // index = base + w . (rot v + o) = i0 + dv . v
        const std::int64_t i0 = base + w.x * o.x + w.y * o.y + w.z * o.z;
        L3 dv;
        for (int j = 0; j < 3; ++j) dv[j] = w.x * in.rot[0][j] + w.y * in.rot[1][j] + w.z * in.rot[2][j];
        for (const auto& v : models[std::size_t(in.model)].voxels) {
            if (v[3] == 0) continue;
            const std::int64_t i = i0 + dv.x * v[0] + dv.y * v[1] + dv.z * v[2];
            if (i < 0 || i >= blocks) throw std::logic_error("load_vox: voxel outside the scene box");  // a bug
            int& m = material[v[3]];
            if (m == 0) {
                const auto& rgb = colours[v[3]];
                const glm::vec3 albedo = glm::min(
                    glm::vec3(srgb8_to_linear(rgb[0]), srgb8_to_linear(rgb[1]), srgb8_to_linear(rgb[2])), glm::vec3(0.95f));
                const auto e = emit.find(v[3]);
                m = s.add_material({albedo, e == emit.end() ? glm::vec3(0.0f) : albedo * e->second, false});
            }
            s.voxels[std::size_t(i)] = std::uint8_t(m);
        }
    }
    s.name = path;
    // A .vox file is a model, not a world: the grid is the model's bounding box, so a fly-through of its free
    // space mostly sees sky. Its default camera path orbits it from the air around the grid (up to one model
    // size away, never below its base: the lower half-space is the ground). The fly-through stays inside the grid
    // whatever the region (its candidates are clipped to the grid), so `--camera-path fly` is unchanged.
    const float margin = float(std::max({s.size.x, s.size.y, s.size.z}));
    s.camera.orbit = true;
    s.camera.region_lo = glm::vec3(-margin, 0.0f, -margin);
    s.camera.region_hi = glm::vec3(s.size) + margin;
    return s;
}

}  // namespace ngi
