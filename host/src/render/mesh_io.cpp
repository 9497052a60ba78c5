// Mesh files through assimp: OBJ (+ .mtl), PLY, glTF 2.0 (.gltf, .glb) -> LoadedMesh (ngi/mesh.hpp says what
// comes out). The file is read once, checked by mesh_precheck.cpp, and handed to assimp from memory through an
// IOSystem that serves only those bytes and, for load_mesh, the files the mesh names (read by ngi's own rule:
// regular files only, within kMaxMeshFileBytes in all). assimp's logging stays off: ngi never creates its
// DefaultLogger, so assimp writes to its NullLogger, and everything it has to say reaches the user as the InputError.
#include <assimp/IOStream.hpp>
#include <assimp/IOSystem.hpp>
#include <assimp/Importer.hpp>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "base/file_util.hpp"
#include "ngi/error.hpp"
#include "ngi/host_memory.hpp"
#include "ngi/material.hpp"
#include "ngi/mesh.hpp"
#include "render/finite.hpp"
#include "render/mesh_precheck.hpp"

namespace ngi {
namespace {

// ---- assimp I/O: the bytes already read and checked, plus the files they name ----------------------------------

class BytesStream : public Assimp::IOStream {
public:
    explicit BytesStream(const std::string& b) : b_(b) {}
    size_t Read(void* out, size_t size, size_t count) override {
        if (size == 0) return 0;
        const size_t n = std::min(count, (b_.size() - pos_) / size);
        if (n > 0) std::memcpy(out, b_.data() + pos_, n * size);
        pos_ += n * size;
        return n;
    }
    size_t Write(const void*, size_t, size_t) override { return 0; }
    aiReturn Seek(size_t offset, aiOrigin origin) override {
        const size_t base = origin == aiOrigin_SET ? 0 : origin == aiOrigin_CUR ? pos_ : b_.size();
        if (origin == aiOrigin_END) {  // assimp's own streams count the offset back from the end
            if (offset > b_.size()) return AI_FAILURE;
            pos_ = b_.size() - offset;
            return AI_SUCCESS;
        }
        if (offset > b_.size() - base) return AI_FAILURE;
        pos_ = base + offset;
        return AI_SUCCESS;
    }
    size_t Tell() const override { return pos_; }
    size_t FileSize() const override { return b_.size(); }
    void Flush() override {}

private:
    const std::string& b_;
    size_t pos_ = 0;
};

class GuardedIO : public Assimp::IOSystem {
public:
    // `main` is served under `main_name`; other names are read from disk only when `sidecars` (load_mesh).
    // `obj`: the mesh is an OBJ, whose importer opens no other file than its material libraries.
    GuardedIO(std::string main_name, const std::string& main, bool sidecars, bool obj)
        : main_name_(std::move(main_name)), main_(main), sidecars_(sidecars), obj_(obj), used_(main.size()) {}

    bool Exists(const char* file) const override {
        if (file == main_name_) return true;
        std::error_code ec;
        return sidecars_ && std::filesystem::exists(file, ec);
    }
    char getOsSeparator() const override { return '/'; }
    Assimp::IOStream* Open(const char* file, const char* mode) override {
        if (mode && std::strchr(mode, 'w')) return nullptr;
        if (file == main_name_) return new BytesStream(main_);
        if (!sidecars_) return nullptr;
        std::error_code ec;
        if (!std::filesystem::exists(file, ec)) {  // assimp goes on without it (import() decides)
            missing_.push_back(file);
            return nullptr;
        }
        try {
            const std::string& bytes = read(file);
            if (obj_) detail::precheck_material_library(bytes, main_name_, file);
            return new BytesStream(bytes);
        } catch (const InputError& e) {  // assimp would swallow it: kept, and thrown after ReadFile
            if (error_.empty()) error_ = e.what();
            return nullptr;
        }
    }
    void Close(Assimp::IOStream* f) override { delete f; }

    // A file the mesh names, read once (the precheck's external buffers are the bytes assimp then gets):
    // directories, FIFOs and devices refused as for every ngi input, the budget spanning all files.
    const std::string& read(const std::string& file) {
        const std::string key = std::filesystem::path(file).lexically_normal().string();
        const auto it = files_.find(key);
        if (it != files_.end()) return it->second;
        detail::require_readable_file(file);
        std::string bytes = detail::read_file(file, "load mesh " + main_name_ + ": read", kMaxMeshFileBytes - used_);
        used_ += bytes.size();
        return files_.emplace(key, std::move(bytes)).first->second;
    }
    const std::string& error() const { return error_; }
    std::size_t files_read() const { return files_.size(); }
    // The bytes of every file read besides the mesh itself (an OBJ's material libraries), by path.
    const std::map<std::string, std::string>& files() const { return files_; }
    const std::vector<std::string>& missing() const { return missing_; }

private:
    std::string main_name_;
    const std::string& main_;
    bool sidecars_;
    bool obj_;
    std::uint64_t used_;
    std::map<std::string, std::string> files_;  // node-based: stable addresses for the streams
    std::string error_;
    std::vector<std::string> missing_;  // files assimp asked for that do not exist
};

// ---- OBJ material names -------------------------------------------------------------------------------------
// `usemtl NAME` of a name no material library defines: assimp logs "Unsupported material requested" and goes on with
// its default material, so the faces after it lost their colour silently (issue 51). Refused, naming the line, the
// name and the names the libraries define. Names as assimp reads them: the rest of the line, blanks trimmed.

std::string_view trimmed(std::string_view v) {
    while (!v.empty() && (v.front() == ' ' || v.front() == '\t')) v.remove_prefix(1);
    while (!v.empty() && (v.back() == ' ' || v.back() == '\t' || v.back() == '\r')) v.remove_suffix(1);
    return v;
}

// (line number, rest of the line) of every line that starts with `keyword` and a blank.
std::vector<std::pair<std::size_t, std::string_view>> statements(const std::string& b, std::string_view keyword) {
    std::vector<std::pair<std::size_t, std::string_view>> out;
    std::size_t pos = 0;
    for (std::size_t line_no = 1; pos < b.size(); ++line_no) {
        const std::size_t nl = b.find('\n', pos);
        std::string_view line = trimmed(std::string_view(b).substr(pos, (nl == std::string::npos ? b.size() : nl) - pos));
        pos = nl == std::string::npos ? b.size() : nl + 1;
        if (line.size() > keyword.size() && line.substr(0, keyword.size()) == keyword &&
            (line[keyword.size()] == ' ' || line[keyword.size()] == '\t'))
            out.emplace_back(line_no, trimmed(line.substr(keyword.size())));
    }
    return out;
}

void check_usemtl_names(const std::string& obj, const std::map<std::string, std::string>& libraries,
                        const std::string& name) {
    std::set<std::string_view> defined;
    std::string files;
    for (const auto& [path, bytes] : libraries) {
        files += (files.empty() ? "" : ", ") + std::filesystem::path(path).filename().string();
        for (const auto& [line, material] : statements(bytes, "newmtl")) defined.insert(material);
    }
    for (const auto& [line, material] : statements(obj, "usemtl")) {
        if (defined.count(material)) continue;
        std::string known;
        for (std::string_view d : defined) {
            if (known.size() > 200) { known += ", ..."; break; }
            known += (known.empty() ? "" : ", ") + std::string(d);
        }
        throw InputError("load mesh " + name + ": OBJ line " + std::to_string(line) + ": usemtl '" +
                         std::string(material).substr(0, 80) + "' names no material of its material library (" + files +
                         " defines " + (known.empty() ? "none" : known) + "): its faces would lose their colour");
    }
}

// ---- colours -----------------------------------------------------------------------------------------------

enum class Format { Obj, Ply, Gltf };

float srgb_to_linear(float c) {
    c = std::clamp(c, 0.0f, 1.0f);
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}
glm::vec3 srgb_to_linear(glm::vec3 c) { return {srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z)}; }
float linear_to_srgb(float c) {
    c = std::clamp(c, 0.0f, 1.0f);
    return c <= 0.0031308f ? c * 12.92f : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}
using detail::finite;
std::string num(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", v);
    return b;
}
std::string rgb(glm::vec3 c) { return num(c.r) + ", " + num(c.g) + ", " + num(c.b); }

// What one assimp material gives a triangle: an albedo of its own (or none: the vertex colours or the default
// decide), a glTF base colour the vertex colours multiply, and its emission.
struct MaterialInfo {
    bool has_colour = false;
    glm::vec3 albedo{0.8f};  // linear
    glm::vec3 emission{0.0f};
};

// `gltf_strength`: the material's KHR_materials_emissive_strength (read by the precheck: assimp 5.2.5 ignores it).
// Negative colours and emission above kMaxEmission are refused: a file that states them is broken, and clamping
// them would light the scene otherwise than it says, silently.
MaterialInfo material_info(const aiMaterial* m, Format format, bool no_material_colours, float gltf_strength,
                           const std::string& where, const std::function<void(const std::string&)>& fail) {
    MaterialInfo info;
    aiString name;
    m->Get(AI_MATKEY_NAME, name);
    aiColor4D c;
    if (format == Format::Gltf) {
        // glTF colour factors are linear (glTF 2.0 §3.9.2); a material without one has base colour 1.
        info.has_colour = true;
        info.albedo = glm::vec3(1.0f);
        if (m->Get(AI_MATKEY_BASE_COLOR, c) == AI_SUCCESS || m->Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS)
            info.albedo = {c.r, c.g, c.b};
    } else if (format == Format::Obj && !no_material_colours &&
               std::strcmp(name.C_Str(), AI_DEFAULT_MATERIAL_NAME) != 0 &&
               m->Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS) {
        // An .mtl's Kd; assimp's own default material (no usemtl / no .mtl) is not the file's colour.
        info.has_colour = true;
        info.albedo = {c.r, c.g, c.b};
        if (!finite(info.albedo)) fail(where + " diffuse colour is not finite");
        if (glm::any(glm::lessThan(info.albedo, glm::vec3(0.0f))))
            fail(where + " diffuse colour (Kd " + rgb(info.albedo) + ") has a negative component");
        info.albedo = srgb_to_linear(info.albedo);
    }
    // A PLY's material is always assimp's invention (PLY files colour their vertices): no colour of its own.
    if (!finite(info.albedo)) fail(where + " base colour is not finite");
    if (glm::any(glm::lessThan(info.albedo, glm::vec3(0.0f))))
        fail(where + " base colour (" + rgb(info.albedo) + ") has a negative component");
    if (m->Get(AI_MATKEY_COLOR_EMISSIVE, c) == AI_SUCCESS) {
        info.emission = {c.r, c.g, c.b};
        if (!finite(info.emission)) fail(where + " emissive colour is not finite");
        if (glm::any(glm::lessThan(info.emission, glm::vec3(0.0f))))
            fail(where + " emissive colour (" + rgb(info.emission) + ") has a negative component");
        float strength = 1.0f;
        if (format == Format::Gltf) strength = gltf_strength;
        else if (m->Get(AI_MATKEY_EMISSIVE_INTENSITY, strength) != AI_SUCCESS) strength = 1.0f;
        const glm::dvec3 e = glm::dvec3(info.emission) * double(strength);  // 1e30 x 1e30 stays finite here
        if (!(std::max({e.x, e.y, e.z}) <= double(kMaxEmission)) || !(strength >= 0.0f))
            fail(where + " emission (" + rgb(info.emission) + ") x strength " + num(strength) +
                 " exceeds the bound of " + std::to_string(int(kMaxEmission)) + " (ngi/material.hpp)");
        info.emission = glm::vec3(e);
    }
    return info;
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
        throw InputError("load mesh " + name + ": it is " + num(extent) + " m across, smaller than " +
                         num(kMinMeshExtent) + " m (mesh files are read as metres: is it in kilometres?)");
    if (spacing > extent / 4096.0f)
        throw InputError("load mesh " + name + ": it is " + num(extent) + " m across at up to " + num(reach) +
                         " m from the origin, where float32 positions step by " + num(spacing) +
                         " m: its detail would be lost (move it near the origin)");
}

// Host bytes per instanced vertex and triangle that loading a mesh into a scene holds at its peak, checked against
// the host-memory budget before convert() allocates. Per vertex: position, normal, has-normal flag and
// compute_vertex_normals' double sum (49 B). Per triangle: 84 B, measured rather than counted -- its indices,
// material before and after quantize() and quantize's group ids come to ~60 B; the peak of load_mesh + make_scene
// (ngi.Scene) on a .glb of 16.76 M instanced triangles and 8.55 M vertices was 1.82 GB, which these constants give.
constexpr std::uint64_t kLoadBytesPerVertex = sizeof(glm::vec3) * 2 + 1 + sizeof(glm::dvec3);
constexpr std::uint64_t kLoadBytesPerTriangle = 84;

LoadedMesh convert(const aiScene* scene, Format format, bool no_material_colours, const std::vector<float>& gltf_strength,
                   const std::string& name) {
    auto fail = [&](const std::string& what) { throw InputError("load mesh " + name + ": " + what); };
    if (!scene->mRootNode) fail("no scene graph");
    std::vector<MaterialInfo> infos;
    for (unsigned i = 0; i < scene->mNumMaterials; ++i)  // glTF: assimp's material i is the file's (its default last)
        infos.push_back(material_info(scene->mMaterials[i], format, no_material_colours,
                                      i < gltf_strength.size() ? gltf_strength[i] : 1.0f,
                                      "material " + std::to_string(i), fail));

    // Instances first, allocations after: a small file may place one mesh under many nodes (a 400 KB .glb with one
    // 20,000-triangle primitive under 838 nodes is 16.8 M triangles). The counts meet the mesh limits and the
    // host-memory budget before anything grows with them, and the arrays are reserved to size (no doubling).
    std::uint64_t instanced_vertices = 0, instanced_faces = 0;
    {
        std::vector<const aiNode*> nodes{scene->mRootNode};
        while (!nodes.empty()) {
            const aiNode* node = nodes.back();
            nodes.pop_back();
            for (unsigned c = 0; c < node->mNumChildren; ++c)
                if (node->mChildren[c]) nodes.push_back(node->mChildren[c]);
            for (unsigned k = 0; k < node->mNumMeshes; ++k) {
                if (node->mMeshes[k] >= scene->mNumMeshes) fail("node refers to a mesh that does not exist");
                instanced_vertices += scene->mMeshes[node->mMeshes[k]]->mNumVertices;
                instanced_faces += scene->mMeshes[node->mMeshes[k]]->mNumFaces;
            }
        }
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
    // Depth-first over the node tree with an explicit stack (assimp's tree came from a checked file, but a walk
    // that cannot overflow the stack needs no argument).
    std::vector<std::pair<const aiNode*, aiMatrix4x4>> stack{{scene->mRootNode, scene->mRootNode->mTransformation}};
    while (!stack.empty()) {
        const auto [node, xf] = stack.back();
        stack.pop_back();
        for (unsigned c = node->mNumChildren; c-- > 0;)
            if (node->mChildren[c]) stack.push_back({node->mChildren[c], xf * node->mChildren[c]->mTransformation});
        const glm::mat4 M = glm::transpose(glm::make_mat4(&xf.a1));  // assimp is row-major
        const glm::mat3 L(M);
        const glm::mat3 N = glm::inverseTranspose(L);
        const bool mirrored = glm::determinant(L) < 0.0f;
        for (unsigned k = 0; k < node->mNumMeshes; ++k) {  // mesh indices and counts: checked by the count above
            const aiMesh* mesh = scene->mMeshes[node->mMeshes[k]];
            const std::string where = "mesh " + std::to_string(node->mMeshes[k]);
            const std::uint32_t base = std::uint32_t(m.positions.size());
            for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
                const aiVector3D& p = mesh->mVertices[v];
                const glm::vec3 w = glm::vec3(M * glm::vec4(p.x, p.y, p.z, 1.0f));
                if (!finite(glm::vec3(p.x, p.y, p.z)) || !finite(w))
                    fail(where + " vertex " + std::to_string(v) + ": position is not finite");
                m.positions.push_back(w);
                glm::vec3 n(0.0f);
                bool ok = false;
                if (mesh->HasNormals()) {
                    const aiVector3D& q = mesh->mNormals[v];
                    if (!finite(glm::vec3(q.x, q.y, q.z)))
                        fail(where + " vertex " + std::to_string(v) + ": normal is not finite");
                    n = N * glm::vec3(q.x, q.y, q.z);
                    const float len = glm::length(n);
                    ok = len > 1e-20f && std::isfinite(len);  // a zero normal says nothing: computed below
                    if (ok) n /= len;
                }
                m.normals.push_back(n);
                has_normal.push_back(ok);
            }
            const MaterialInfo info =
                mesh->mMaterialIndex < infos.size() ? infos[mesh->mMaterialIndex] : MaterialInfo{};
            const aiColor4D* colours = mesh->HasVertexColors(0) ? mesh->mColors[0] : nullptr;
            for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
                const aiFace& face = mesh->mFaces[f];
                if (face.mNumIndices != 3) {
                    ++out.dropped_primitives;
                    continue;
                }
                glm::uvec3 t(face.mIndices[0], face.mIndices[1], face.mIndices[2]);
                for (int j = 0; j < 3; ++j)
                    if (t[j] >= mesh->mNumVertices)
                        fail(where + " face " + std::to_string(f) + ": vertex index " + std::to_string(t[j]) +
                             " is out of range (" + std::to_string(mesh->mNumVertices) + " vertices)");
                Material mat;
                mat.emission = info.emission;
                glm::vec3 vc(1.0f);
                if (colours) {
                    glm::vec3 sum(0.0f);
                    for (int j = 0; j < 3; ++j) {
                        const aiColor4D& c = colours[t[j]];
                        const glm::vec3 rgb(c.r, c.g, c.b);
                        if (!finite(rgb)) fail(where + " vertex " + std::to_string(t[j]) + ": colour is not finite");
                        sum += format == Format::Gltf ? glm::clamp(rgb, 0.0f, 1.0f) : srgb_to_linear(rgb);
                    }
                    vc = sum / 3.0f;
                }
                if (format == Format::Gltf) mat.albedo = info.albedo * vc;  // COLOR_0 multiplies the base colour
                else if (info.has_colour) mat.albedo = info.albedo;
                else if (colours) mat.albedo = vc;
                else mat.albedo = Material{}.albedo;
                mat.albedo = glm::clamp(mat.albedo, glm::vec3(0.0f), glm::vec3(0.95f));
                if (mirrored) std::swap(t.y, t.z);  // keep counter-clockwise seen from the front
                m.triangles.push_back(t + base);
                tri_material.push_back(mat);
            }
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
    const std::string ext = detail::lower_extension(name);
    const std::filesystem::path dir = std::filesystem::path(name).parent_path();
    Assimp::Importer importer;
    auto* io = new GuardedIO(name, bytes, sidecars, ext == ".obj");
    importer.SetIOHandler(io);  // owned by the importer from here
    detail::MeshPrecheckFacts facts;
    detail::precheck_mesh(bytes, name, ext, [&](const std::string& uri) -> const std::string& {
        if (!sidecars)
            throw InputError("load mesh " + name + ": external buffer '" + uri + "' (only the file's own bytes are "
                             "read here)");
        return io->read((dir / uri).string());
    }, &facts);
    const Format format = ext == ".obj" ? Format::Obj : ext == ".ply" ? Format::Ply : Format::Gltf;
    // Two steps: import and validate (indices in range, counts consistent), then post-process. In between, each
    // mesh's primitive-type flags are recomputed from its faces: importers set them themselves, and
    // TriangulateProcess asserts -- aborting the process, in Debian's build -- when a mesh flagged as holding
    // polygons holds none (fuzz_mesh found a PLY doing that).
    const aiScene* scene = importer.ReadFile(name, aiProcess_ValidateDataStructure);
    if (!io->error().empty()) throw InputError(io->error());
    if (!scene) throw InputError("load mesh " + name + ": " + importer.GetErrorString());
    for (unsigned i = 0; i < scene->mNumMeshes; ++i) {
        aiMesh* mesh = scene->mMeshes[i];
        unsigned types = 0;
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const unsigned n = mesh->mFaces[f].mNumIndices;
            types |= n == 1 ? aiPrimitiveType_POINT : n == 2 ? aiPrimitiveType_LINE : n == 3 ? aiPrimitiveType_TRIANGLE
                                                                                            : aiPrimitiveType_POLYGON;
        }
        mesh->mPrimitiveTypes = types;
    }
    // Points and lines reach convert() as 1- and 2-index faces: counted and dropped there.
    scene = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                         aiProcess_ValidateDataStructure);
    if (!io->error().empty()) throw InputError(io->error());
    if (!scene) throw InputError("load mesh " + name + ": " + importer.GetErrorString());
    if (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) throw InputError("load mesh " + name + ": the file is incomplete");
    // An OBJ naming a material library that is not there would load in ngi's default grey, silently (assimp only
    // logs it, after also trying <name>.mtl): refused, saying what to do. parse_mesh reads no material library.
    if (format == Format::Obj && io->files_read() == 0 && !io->missing().empty())
        throw InputError("load mesh " + name + ": its material library " + io->missing().front() + " does not "
                         "exist: its colours would be lost (put the .mtl beside it, or remove the mtllib line to "
                         "load it in the default colour)");
    if (format == Format::Obj && io->files_read() > 0) check_usemtl_names(bytes, io->files(), name);
    // An OBJ's materials have colours of the file's only when its .mtl was read (assimp invents the rest).
    return convert(scene, format, format == Format::Obj && io->files_read() == 0, facts.gltf_emissive_strength, name);
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
