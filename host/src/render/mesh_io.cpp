// Mesh files -> LoadedMesh (ngi/mesh.hpp says what comes out). The file is read once and handed to the reader of its
// format (mesh_source.hpp: one parser per format); what they return is triangulated, its identical vertices joined,
// its instances placed, checked against the limits and turned into ngi's mesh here, the same for every format.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>
#include <tuple>
#include <unordered_map>
#include <vector>

#include <glm/gtc/matrix_inverse.hpp>

#include "base/file_util.hpp"
#include "ngi/error.hpp"
#include "ngi/host_memory.hpp"
#include "ngi/material.hpp"
#include "ngi/mesh.hpp"
#include "render/finite.hpp"
#include "render/mesh_source.hpp"

namespace ngi {
namespace detail {

void mesh_fail(const std::string& name, const std::string& what) { throw InputError("load mesh " + name + ": " + what); }

std::string mesh_number(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", v);
    return b;
}

std::string mesh_printable(const std::string& s) {
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

static std::string mesh_rgb(glm::vec3 c) {
    return mesh_number(c.r) + ", " + mesh_number(c.g) + ", " + mesh_number(c.b);
}

// Negative colours and emission above kMaxEmission are refused: a file that states them is broken, and clamping them
// would light the scene otherwise than it says, silently.
void check_colour(const std::string& name, const std::string& what, glm::vec3 c) {
    if (!finite(c)) mesh_fail(name, what + " is not finite");
    if (glm::any(glm::lessThan(c, glm::vec3(0.0f))))
        mesh_fail(name, what + " (" + mesh_rgb(c) + ") has a negative component");
}

glm::vec3 checked_emission(const std::string& name, const std::string& where, glm::vec3 emission, double strength) {
    check_colour(name, where + " emissive colour", emission);
    const glm::dvec3 e = glm::dvec3(emission) * strength;  // 1e30 x 1e30 stays finite here
    if (!(std::max({e.x, e.y, e.z}) <= double(kMaxEmission)) || !(strength >= 0.0))
        mesh_fail(name, where + " emission (" + mesh_rgb(emission) + ") x strength " + mesh_number(strength) +
                            " exceeds the bound of " + std::to_string(int(kMaxEmission)) + " (ngi/material.hpp)");
    return glm::vec3(e);
}

const std::string& MeshSidecars::read(const std::string& path) {
    if (!enabled_) mesh_fail(mesh_name_, "'" + path + "' (only the file's own bytes are read here)");
    const std::string key = std::filesystem::path(path).lexically_normal().string();
    const auto it = files_.find(key);
    if (it != files_.end()) return it->second;
    require_readable_file(path);
    std::string bytes = read_file(path, "load mesh " + mesh_name_ + ": read", kMaxMeshFileBytes - used_);
    used_ += bytes.size();
    return files_.emplace(key, std::move(bytes)).first->second;
}

}  // namespace detail

namespace {

using detail::finite;
using detail::MeshFile;
using detail::MeshFormat;
using detail::MeshMaterial;
using detail::MeshPart;

float srgb_to_linear(float c) {
    c = std::clamp(c, 0.0f, 1.0f);
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}
glm::vec3 srgb_to_linear(glm::vec3 c) { return {srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z)}; }
float linear_to_srgb(float c) {
    c = std::clamp(c, 0.0f, 1.0f);
    return c <= 0.0031308f ? c * 12.92f : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

// ---- polygons -> triangles ----------------------------------------------------------------------------------
// The rule of the loader ngi used before issue 49, so that a file splits as it did: a quad
// is fanned from its concave corner, if any, else from its first; a larger polygon is projected onto the plane of
// its largest Newell-normal component and ear-clipped, starting after the last ear found (a convex polygon gives
// (n-1, 0, 1), (n-1, 1, 2), ...). A polygon without an ear (not simple) is fanned (that loader dropped its rest). Where a
// polygon's triangles begin at the corner the previous polygon's began at, they are rotated to begin elsewhere (the
// same triangles, the same winding: only the vertex numbering follows from it).
struct PolygonSplitter {
    const std::vector<glm::vec3>& pos;
    std::vector<glm::uvec3>& out;
    std::uint32_t last_first = UINT32_MAX;
    std::vector<glm::vec2> flat;
    std::vector<char> done;
    // Point-in-triangle tests one polygon may spend before the rest of it is fanned: ear clipping is O(n^2) per ear on
    // a hostile polygon, and a face line may hold millions of corners.
    static constexpr std::uint64_t kEarBudget = std::uint64_t(1) << 26;

    void emit(glm::uvec3 t) {
        if (t.x == last_first) t = {t.z, t.x, t.y};
        last_first = t.x;
        out.push_back(t);
    }
    static glm::vec3 unit(glm::vec3 v) { return v / std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }
    static float area2(glm::vec2 a, glm::vec2 b, glm::vec2 c) {
        return 0.5f * (a.x * (c.y - b.y) + b.x * (a.y - c.y) + c.x * (b.y - a.y));
    }
    static bool inside(glm::vec2 p0, glm::vec2 p1, glm::vec2 p2, glm::vec2 pp) {  // barycentric, strict
        const glm::vec2 v0 = p1 - p0, v1 = p2 - p0, v2 = pp - p0;
        float d00 = v0.x * v0.x + v0.y * v0.y, d01 = v0.x * v1.x + v0.y * v1.y, d02 = v0.x * v2.x + v0.y * v2.y;
        float d11 = v1.x * v1.x + v1.y * v1.y, d12 = v1.x * v2.x + v1.y * v2.y;
        const float inv = 1.0f / (d00 * d11 - d01 * d01);
        d11 = (d11 * d02 - d01 * d12) * inv;
        d00 = (d00 * d12 - d01 * d02) * inv;
        return d11 > 0 && d00 > 0 && d11 + d00 < 1;
    }

    void add(const std::uint32_t* idx, std::uint32_t n) {
        if (n == 3) return emit({idx[0], idx[1], idx[2]});
        if (n == 4) {
            std::uint32_t s = 0;
            for (std::uint32_t i = 0; i < 4; ++i) {
                const glm::vec3 v = pos[idx[i]];
                const glm::vec3 left = unit(pos[idx[(i + 3) % 4]] - v), diag = unit(pos[idx[(i + 2) % 4]] - v),
                                right = unit(pos[idx[(i + 1) % 4]] - v);
                const float angle = std::acos(glm::dot(left, diag)) + std::acos(glm::dot(right, diag));
                if (angle > 3.1415926538f) {
                    s = i;
                    break;
                }
            }
            glm::uvec3 a(idx[s], idx[(s + 1) % 4], idx[(s + 2) % 4]), b(idx[s], idx[(s + 2) % 4], idx[(s + 3) % 4]);
            if (a.x == last_first) {  // fan from the opposite corner: the same diagonal
                a = {a.z, a.x, a.y};
                b = {b.y, b.z, b.x};
            }
            last_first = a.x;
            out.push_back(a);
            out.push_back(b);
            return;
        }
        glm::vec3 nn(0.0f);  // Newell normal
        for (std::uint32_t k = 0; k < n; ++k) {
            const glm::vec3 lo = pos[idx[k]], c = pos[idx[(k + 1) % n]], hi = pos[idx[(k + 2) % n]];
            nn.z += c.x * (hi.y - lo.y);
            nn.x += c.y * (hi.z - lo.z);
            nn.y += c.z * (hi.x - lo.x);
        }
        const float ax = std::abs(nn.x), ay = std::abs(nn.y), az = std::abs(nn.z);
        int ac = 0, bc = 1;
        float inv = nn.z;
        if (ax > ay) {
            if (ax > az) ac = 1, bc = 2, inv = nn.x;
        } else if (ay > az) {
            ac = 2, bc = 0, inv = nn.y;
        }
        if (inv < 0.0f) std::swap(ac, bc);
        flat.resize(n);
        done.assign(n, 0);
        for (std::uint32_t k = 0; k < n; ++k) flat[k] = {pos[idx[k]][ac], pos[idx[k]][bc]};
        const int max = int(n);
        int num = max, ear = 0, prev = max - 1, next = 0;
        std::vector<glm::uvec3> local;
        std::uint64_t spent = 0;
        while (num > 3 && spent < kEarBudget) {
            int found = 0;
            for (ear = next;; prev = ear, ear = next) {
                if (++spent >= kEarBudget) break;
                for (next = ear + 1; done[std::size_t(next >= max ? next = 0 : next)]; ++next) {}
                if (next < ear && ++found == 2) break;
                const glm::vec2 p0 = flat[std::size_t(prev)], p1 = flat[std::size_t(ear)], p2 = flat[std::size_t(next)];
                if (area2(p0, p1, p2) > 0) continue;  // not convex
                int t = 0;
                spent += std::uint64_t(max);
                if (spent >= kEarBudget) break;
                for (; t < max; ++t) {
                    const glm::vec2 v = flat[std::size_t(t)];
                    if (v != p1 && v != p2 && v != p0 && inside(p0, p1, p2, v)) break;
                }
                if (t == max) break;
            }
            if (found == 2 || spent >= kEarBudget) break;
            local.push_back(glm::uvec3(std::uint32_t(prev), std::uint32_t(ear), std::uint32_t(next)));
            done[std::size_t(ear)] = 1;
            --num;
        }
        std::vector<std::uint32_t> rest;
        for (std::uint32_t k = 0; k < n; ++k)
            if (!done[k]) rest.push_back(k);
        for (std::size_t k = 1; k + 1 < rest.size(); ++k) local.push_back({rest[0], rest[k], rest[k + 1]});
        for (const glm::uvec3 t : local) emit({idx[t.x], idx[t.y], idx[t.z]});
    }
};

// ---- a part -> triangles over its distinct vertices ---------------------------------------------------------

// A part triangulated, with its identical vertices (position, normal, colour and texture coordinate alike, bit for
// bit) joined: `vertex` holds the part's index of each distinct vertex, `triangles` index into `vertex`.
struct JoinedPart {
    std::vector<std::uint32_t> vertex;
    std::vector<glm::uvec3> triangles;
};

JoinedPart join_part(const MeshPart& p) {
    JoinedPart j;
    std::vector<glm::uvec3> tris;
    tris.reserve(p.corners.size());
    PolygonSplitter split{p.positions, tris, UINT32_MAX, {}, {}};
    std::size_t at = 0;
    const bool polygons = std::any_of(p.sizes.begin(), p.sizes.end(), [](std::uint32_t s) { return s > 3; });
    for (const std::uint32_t n : p.sizes) {
        if (polygons) split.add(p.corners.data() + at, n);
        else tris.push_back({p.corners[at], p.corners[at + 1], p.corners[at + 2]});
        at += n;
    }
    struct Key {
        float v[11];
        bool operator==(const Key& o) const { return std::memcmp(v, o.v, sizeof v) == 0; }
    };
    struct KeyHash {
        std::size_t operator()(const Key& k) const {
            std::uint64_t h = 1469598103934665603ull;
            const unsigned char* c = reinterpret_cast<const unsigned char*>(k.v);
            for (std::size_t i = 0; i < sizeof k.v; ++i) h = (h ^ c[i]) * 1099511628211ull;
            return std::size_t(h);
        }
    };
    std::unordered_map<Key, std::uint32_t, KeyHash> seen;
    std::vector<std::uint32_t> joined(p.positions.size());
    for (std::size_t i = 0; i < p.positions.size(); ++i) {
        Key k{};
        std::memcpy(k.v, &p.positions[i], 12);
        if (!p.normals.empty()) std::memcpy(k.v + 3, &p.normals[i], 12);
        if (!p.colours.empty()) std::memcpy(k.v + 6, &p.colours[i], 12);
        if (!p.texcoords.empty()) std::memcpy(k.v + 9, &p.texcoords[i], 8);
        const auto [it, fresh] = seen.emplace(k, std::uint32_t(j.vertex.size()));
        if (fresh) j.vertex.push_back(std::uint32_t(i));
        joined[i] = it->second;
    }
    j.triangles.reserve(tris.size());
    for (const glm::uvec3 t : tris) j.triangles.push_back({joined[t.x], joined[t.y], joined[t.z]});
    return j;
}

// Per-triangle materials -> at most 255 palette entries. Exact duplicates share an entry. When more remain, colours
// are binned on a grid in sRGB (perceptually even steps; 64, 32, 16, 8, 4, 2, then 1 level per channel, the first
// that fits) and emission on a log2 grid of as many steps per 8 octaves; each bin becomes the mean of its
// triangles' linear colours. The last resort (one level) leaves two bins, emissive or not. Entries are numbered in
// order of first use, so the result depends only on the file.
std::vector<Material> quantize(std::vector<Material>& tri, std::vector<std::uint8_t>& index) {
    constexpr std::size_t kMax = 255;
    using Key = std::tuple<std::int64_t, std::int64_t, std::int64_t, std::int64_t, std::int64_t, std::int64_t>;
    auto bits = [](float f) { std::int32_t i; std::memcpy(&i, &f, 4); return std::int64_t(i); };
    auto group = [&](auto&& key_of) {
        std::map<Key, std::size_t> ids;
        std::vector<std::size_t> id(tri.size());
        for (std::size_t i = 0; i < tri.size() && ids.size() <= kMax; ++i)
            id[i] = ids.emplace(key_of(tri[i]), ids.size()).first->second;
        return std::make_pair(ids.size(), id);
    };
    auto exact = group([&](const Material& m) {
        return Key{bits(m.albedo.x), bits(m.albedo.y), bits(m.albedo.z), bits(m.emission.x), bits(m.emission.y),
                   bits(m.emission.z)};
    });
    for (int levels : {0, 64, 32, 16, 8, 4, 2, 1, -1}) {
        auto g = levels == 0 ? exact : group([&](const Material& m) {
            if (levels < 0) return Key{0, 0, 0, m.emission != glm::vec3(0.0f), 0, 0};
            auto a = [&](float v) { return std::int64_t(std::lround(linear_to_srgb(v) * float(levels - 1))); };
            auto e = [&](float v) {
                if (v <= 0.0f) return std::int64_t(-1000000);
                return std::int64_t(std::floor(std::log2(v) * float(levels) / 8.0f));
            };
            return Key{a(m.albedo.x), a(m.albedo.y), a(m.albedo.z), e(m.emission.x), e(m.emission.y), e(m.emission.z)};
        });
        if (g.first > kMax) continue;
        std::vector<glm::dvec3> albedo(g.first, glm::dvec3(0.0)), emission(g.first, glm::dvec3(0.0));
        std::vector<std::size_t> n(g.first, 0);
        for (std::size_t i = 0; i < tri.size(); ++i) {
            albedo[g.second[i]] += glm::dvec3(tri[i].albedo);
            emission[g.second[i]] += glm::dvec3(tri[i].emission);
            ++n[g.second[i]];
        }
        std::vector<Material> out(g.first);
        for (std::size_t k = 0; k < g.first; ++k)
            out[k] = {glm::vec3(albedo[k] / double(n[k])), glm::vec3(emission[k] / double(n[k])), false};
        index.resize(tri.size());
        for (std::size_t i = 0; i < tri.size(); ++i) index[i] = std::uint8_t(g.second[i] + 1);
        return out;
    }
    throw std::logic_error("quantize: the last level always fits");  // two bins at most
}

// ---- the scene graph -> one TriangleMesh ------------------------------------------------------------------

// A mesh the renderer can resolve: at least kMinMeshExtent across (files are read as metres; a 1e-20 m mesh is no
// block of any grid and rendered as nothing), and not so far from the origin that float32 positions lose its
// detail (at 1e7 m floats step by 1 m: a 0.5 m mesh there collapsed into an all-sky frame). The rule: the float
// spacing at its largest coordinate stays under 1/4096 of its size.
constexpr float kMinMeshExtent = 1e-3f;
void check_extent(const TriangleMesh& m, const std::string& name) {
    const auto [lo, hi] = mesh_bounds(m);
    const float extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    const float reach = std::max({std::abs(lo.x), std::abs(lo.y), std::abs(lo.z), std::abs(hi.x), std::abs(hi.y),
                                  std::abs(hi.z)});
    const float spacing = std::nextafter(reach, INFINITY) - reach;
    if (!(extent >= kMinMeshExtent))
        throw InputError("load mesh " + name + ": it is " + detail::mesh_number(extent) + " m across, smaller than " +
                         detail::mesh_number(kMinMeshExtent) + " m (mesh files are read as metres: is it in kilometres?)");
    if (spacing > extent / 4096.0f)
        throw InputError("load mesh " + name + ": it is " + detail::mesh_number(extent) + " m across at up to " + detail::mesh_number(reach) +
                         " m from the origin, where float32 positions step by " + detail::mesh_number(spacing) +
                         " m: its detail would be lost (move it near the origin)");
}

// Host bytes per instanced vertex and triangle that loading a mesh into a scene holds at its peak, checked against
// the host-memory budget before convert() allocates. Per vertex: position, normal, has-normal flag and
// compute_vertex_normals' double sum (49 B). Per triangle: 84 B, measured rather than counted -- its indices,
// material before and after quantize() and quantize's group ids come to ~60 B; the peak of load_mesh + make_scene
// (ngi.Scene) on a .glb of 16.76 M instanced triangles and 8.55 M vertices was 1.82 GB, which these constants give.
constexpr std::uint64_t kLoadBytesPerVertex = sizeof(glm::vec3) * 2 + 1 + sizeof(glm::dvec3);
constexpr std::uint64_t kLoadBytesPerTriangle = 84;

LoadedMesh convert(const MeshFile& file, const std::string& name) {
    auto fail = [&](const std::string& what) { detail::mesh_fail(name, what); };
    std::vector<JoinedPart> joined;
    joined.reserve(file.parts.size());
    for (const MeshPart& p : file.parts) joined.push_back(join_part(p));

    // Instances first, allocations after: a small file may place one mesh under many nodes (a 400 KB .glb with one
    // 20,000-triangle primitive under 838 nodes is 16.8 M triangles). The counts meet the mesh limits and the
    // host-memory budget before anything grows with them, and the arrays are reserved to size (no doubling).
    std::uint64_t instanced_vertices = 0, instanced_faces = 0;
    for (const detail::MeshInstance& in : file.instances) {
        instanced_vertices += joined[in.part].vertex.size();
        instanced_faces += joined[in.part].triangles.size();
    }
    if (instanced_vertices > kMaxMeshVertices)
        fail(std::to_string(instanced_vertices) + " vertices, more than the limit of " +
             std::to_string(kMaxMeshVertices) + " (every node's instance counted)");
    if (instanced_faces > kMaxMeshTriangles)
        fail(std::to_string(instanced_faces) + " faces, more than the limit of " + std::to_string(kMaxMeshTriangles) +
             " triangles (every node's instance counted)");
    check_host_memory("load mesh " + name + ": " + std::to_string(instanced_faces) + " triangles and " +
                          std::to_string(instanced_vertices) + " vertices (every node's instance counted)",
                      instanced_vertices * kLoadBytesPerVertex + instanced_faces * kLoadBytesPerTriangle);

    LoadedMesh out;
    TriangleMesh& m = out.mesh;
    std::vector<Material> tri_material;
    std::vector<char> has_normal;
    m.positions.reserve(std::size_t(instanced_vertices));
    m.normals.reserve(std::size_t(instanced_vertices));
    has_normal.reserve(std::size_t(instanced_vertices));
    m.triangles.reserve(std::size_t(instanced_faces));
    tri_material.reserve(std::size_t(instanced_faces));
    for (std::size_t k = 0; k < file.instances.size(); ++k) {
        const detail::MeshInstance& in = file.instances[k];
        const MeshPart& part = file.parts[in.part];
        const JoinedPart& jp = joined[in.part];
        const glm::mat4& M = in.transform;
        const glm::mat3 L(M);
        const glm::mat3 N = glm::inverseTranspose(L);
        const bool mirrored = glm::determinant(L) < 0.0f;
        const std::uint32_t base = std::uint32_t(m.positions.size());
        for (const std::uint32_t v : jp.vertex) {
            const glm::vec3 p = part.positions[v];
            const glm::vec3 w = glm::vec3(M * glm::vec4(p.x, p.y, p.z, 1.0f));
            if (!finite(w))
                fail("instance " + std::to_string(k) + " vertex " + std::to_string(v) +
                     ": position is not finite after its node's transform");
            m.positions.push_back(w);
            glm::vec3 n(0.0f);
            bool ok = false;
            if (!part.normals.empty()) {
                n = N * part.normals[v];
                const float len = glm::length(n);
                ok = len > 1e-20f && std::isfinite(len);  // a zero normal says nothing: computed below
                if (ok) n /= len;
            }
            m.normals.push_back(n);
            has_normal.push_back(ok);
        }
        out.dropped_primitives += part.dropped_primitives;
        MeshMaterial info = part.material >= 0 ? file.materials[std::size_t(part.material)] : file.default_material;
        if (file.format == MeshFormat::Obj) info.albedo = srgb_to_linear(info.albedo);  // an .mtl's Kd is sRGB
        const bool gltf = file.format == MeshFormat::Gltf;
        for (glm::uvec3 t : jp.triangles) {
            Material mat;
            mat.emission = info.emission;
            glm::vec3 vc(1.0f);
            if (!part.colours.empty()) {
                glm::vec3 sum(0.0f);
                for (int j = 0; j < 3; ++j) {
                    const glm::vec3 c = part.colours[jp.vertex[t[j]]];
                    sum += gltf ? glm::clamp(c, 0.0f, 1.0f) : srgb_to_linear(c);
                }
                vc = sum / 3.0f;
            }
            if (gltf) mat.albedo = info.albedo * vc;  // COLOR_0 multiplies the base colour
            else if (info.has_colour) mat.albedo = info.albedo;
            else if (!part.colours.empty()) mat.albedo = vc;
            else mat.albedo = Material{}.albedo;
            mat.albedo = glm::clamp(mat.albedo, glm::vec3(0.0f), glm::vec3(0.95f));
            if (mirrored) std::swap(t.y, t.z);  // keep counter-clockwise seen from the front
            m.triangles.push_back(t + base);
            tri_material.push_back(mat);
        }
    }

    // Zero-area triangles cannot be hit and have no normal: dropped (counted). Cross product in double, so only
    // truly degenerate ones (repeated or collinear corners) go.
    std::size_t kept = 0;
    for (std::size_t i = 0; i < m.triangles.size(); ++i) {
        const glm::uvec3 t = m.triangles[i];
        const glm::dvec3 a(m.positions[t.x]), b(m.positions[t.y]), c(m.positions[t.z]);
        if (glm::length(glm::cross(b - a, c - a)) == 0.0) {
            ++out.dropped_degenerate;
            continue;
        }
        m.triangles[kept] = t;
        tri_material[kept] = tri_material[i];
        ++kept;
    }
    m.triangles.resize(kept);
    tri_material.resize(kept);
    if (kept == 0)
        fail(out.dropped_degenerate + out.dropped_primitives > 0
                 ? "no triangle with an area (" + std::to_string(out.dropped_degenerate) + " degenerate, " +
                       std::to_string(out.dropped_primitives) + " points or lines)"
                 : "the file has no triangles");
    check_extent(m, name);

    // Only the vertices the kept triangles use, in order of first use (a stable, file-determined numbering).
    std::vector<std::uint32_t> remap(m.positions.size(), UINT32_MAX);
    TriangleMesh c;
    std::vector<char> c_has;
    for (glm::uvec3& t : m.triangles)
        for (int j = 0; j < 3; ++j) {
            std::uint32_t& r = remap[t[j]];
            if (r == UINT32_MAX) {
                r = std::uint32_t(c.positions.size());
                c.positions.push_back(m.positions[t[j]]);
                c.normals.push_back(m.normals[t[j]]);
                c_has.push_back(has_normal[t[j]]);
            }
            t[j] = r;
        }
    c.triangles = std::move(m.triangles);
    // The file's normals where it has them, else area-weighted ones.
    TriangleMesh smooth = c;
    compute_vertex_normals(smooth);
    for (std::size_t i = 0; i < c.normals.size(); ++i)
        if (!c_has[i]) c.normals[i] = smooth.normals[i];
    out.materials = quantize(tri_material, c.materials);
    out.mesh = std::move(c);
    validate_mesh(out.mesh, out.materials.size() + 1, name);
    return out;
}

LoadedMesh import(const std::string& bytes, const std::string& name, bool sidecars) {
    if (bytes.empty()) detail::mesh_fail(name, "the file is empty");
    const std::string ext = detail::lower_extension(name);
    detail::MeshSidecars files(name, sidecars, bytes.size());
    if (ext == ".obj") return convert(detail::read_obj(bytes, name, files), name);
    if (ext == ".ply") return convert(detail::read_ply(bytes, name), name);
    return convert(detail::read_gltf(bytes, name, ext == ".glb", files), name);
}

}  // namespace

LoadedMesh load_mesh(const std::string& path) {
    if (!is_mesh_path(path))
        throw InputError("load mesh " + path + ": not a mesh file extension (.obj, .ply, .gltf, .glb)");
    detail::require_readable_file(path);
    const std::string bytes = detail::read_file(path, "load mesh", kMaxMeshFileBytes);
    return import(bytes, path, true);
}

LoadedMesh parse_mesh(const std::string& bytes, const std::string& name) {
    if (!is_mesh_path(name))
        throw InputError("load mesh " + name + ": not a mesh file extension (.obj, .ply, .gltf, .glb)");
    return import(bytes, name, false);
}

}  // namespace ngi
