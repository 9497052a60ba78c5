// glTF 2.0 (.gltf with embedded or external buffers, .glb) -> MeshFile through tinygltf (Debian's libtinygltf-dev,
// header-only: its implementation is compiled here, so the fuzz build instruments it). tinygltf parses the JSON and
// decodes the buffers; this file checks what glTF states against what is there before reading any of it: every
// accessor inside its buffer view, every view inside its buffer, buffers inside the bytes behind them (the GLB's BIN
// chunk, a data URI, an external file), accessors without a view at most 16 x the file's size in all, attributes of
// one primitive of equal count, every index below the vertex count, the node graph a forest at most 64 deep, JSON
// nesting at most 128 (tinygltf recurses through `extras`). Read: POSITION, NORMAL, COLOR_0 (float or normalized
// unsigned bytes / shorts), TEXCOORD_0 (to keep apart the vertices the file keeps apart), indices, every primitive
// mode (points and lines counted and dropped), the default scene's node tree with its transforms, materials'
// baseColorFactor, emissiveFactor and KHR_materials_emissive_strength. No image is decoded (ngi reads no texture).
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#define TINYGLTF_NO_FS
#include <fstream>  // tinygltf's writer needs it even without its file callbacks
#include <tiny_gltf.h>

#include <algorithm>
#include <cfloat>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "ngi/error.hpp"
#include "ngi/mesh.hpp"
#include "render/finite.hpp"
#include "render/mesh_source.hpp"

namespace ngi::detail {
namespace {

constexpr int kMaxGltfDepth = 64;

std::uint32_t glb_u32(const std::string& b, std::size_t at) {
    std::uint32_t v = 0;
    for (int k = 3; k >= 0; --k) v = v << 8 | static_cast<unsigned char>(b[at + std::size_t(k)]);
    return v;
}

// What tinygltf's file callbacks report back (they may not throw through it).
struct GltfFiles {
    MeshSidecars* sidecars;
    std::string name;   // the glTF, for messages
    std::string base;   // the glTF's folder, with its separator ("" in the working directory)
    std::string error;  // the first refusal
};

bool gltf_file_exists(const std::string& path, void* user) {
    // tinygltf also looks in the working directory: only the glTF's own folder is searched.
    const GltfFiles& f = *static_cast<GltfFiles*>(user);
    return path.compare(0, f.base.size(), f.base) == 0 && (!f.base.empty() || path.compare(0, 2, "./") != 0);
}
std::string gltf_expand_path(const std::string& path, void*) { return path; }
bool gltf_read_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
    GltfFiles& f = *static_cast<GltfFiles*>(user);
    try {
        if (!f.sidecars->enabled()) mesh_fail("", "");
        const std::string& bytes = f.sidecars->read(path);
        out->assign(bytes.begin(), bytes.end());
        return true;
    } catch (const InputError& e) {
        if (f.error.empty())
            f.error = f.sidecars->enabled() ? e.what()
                                            : "load mesh " + f.name + ": external buffer '" + path +
                                                  "' (only the file's own bytes are read here)";
        if (err) *err += "not read";
        return false;
    }
}
bool gltf_write_file(std::string*, const std::string&, const std::vector<unsigned char>&, void*) { return false; }
bool gltf_skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                     void*) {
    return true;
}

// The checks of a loaded model and the reading of its accessors.
struct GltfReader {
    const tinygltf::Model& m;
    const std::string& name;
    std::uint64_t input_bytes;

    [[noreturn]] void fail(const std::string& what) const { mesh_fail(name, what); }

    void check_index(int i, std::size_t n, const std::string& where, const char* of_what) const {
        if (i < 0 || std::size_t(i) >= n)
            fail(where + " refers to " + std::to_string(i) + ", not one of the " + std::to_string(n) + " " + of_what);
    }

    // `count` elements of `elem` bytes at `offset` in view `v` (stride: the view's, at least `elem`).
    void check_in_view(int v, std::size_t offset, std::uint64_t count, std::uint64_t elem, const std::string& where) const {
        check_index(v, m.bufferViews.size(), where + " bufferView", "buffer views");
        const tinygltf::BufferView& view = m.bufferViews[std::size_t(v)];
        const std::uint64_t stride = std::max<std::uint64_t>(view.byteStride, elem);
        if (offset > view.byteLength)
            fail(where + " byteOffset " + std::to_string(offset) + " is past buffer view " + std::to_string(v));
        const std::uint64_t need = offset + (count - 1) * stride + elem;  // count <= 3 x 2^24, stride <= 252
        if (count > 0 && need > view.byteLength)
            fail(where + ": " + std::to_string(count) + " elements need " + std::to_string(need) +
                 " bytes, buffer view " + std::to_string(v) + " has " + std::to_string(view.byteLength));
    }

    void check_structure(bool binary) const {
        for (std::size_t i = 0; i < m.buffers.size(); ++i)
            if (binary && i > 0 && m.buffers[i].uri.empty())
                fail("glTF buffer " + std::to_string(i) + " has no uri and no GLB BIN chunk");
        for (std::size_t i = 0; i < m.bufferViews.size(); ++i) {
            const tinygltf::BufferView& v = m.bufferViews[i];
            const std::string where = "glTF bufferView " + std::to_string(i);
            check_index(v.buffer, m.buffers.size(), where + " buffer", "buffers");
            const std::size_t have = m.buffers[std::size_t(v.buffer)].data.size();
            if (v.byteOffset > have || v.byteLength > have - v.byteOffset)
                fail(where + " (offset " + std::to_string(v.byteOffset) + ", " + std::to_string(v.byteLength) +
                     " bytes) runs past buffer " + std::to_string(v.buffer) + " (" + std::to_string(have) + " bytes)");
            if (v.byteStride > 252) fail(where + " byteStride " + std::to_string(v.byteStride) + " is more than glTF's 252");
        }
        std::uint64_t unbacked = 0;
        const std::uint64_t unbacked_limit = 16 * input_bytes + (std::uint64_t(1) << 20);
        for (std::size_t i = 0; i < m.accessors.size(); ++i) {
            const tinygltf::Accessor& a = m.accessors[i];
            const std::string where = "glTF accessor " + std::to_string(i);
            const int csize = a.componentType >= 0 ? tinygltf::GetComponentSizeInBytes(std::uint32_t(a.componentType)) : -1;
            const int n = a.type >= 0 ? tinygltf::GetNumComponentsInType(std::uint32_t(a.type)) : -1;
            if (csize <= 0 || n <= 0) fail(where + " has no glTF componentType and type");
            if (a.count > 3 * std::uint64_t(kMaxMeshTriangles))
                fail(where + " claims " + std::to_string(a.count) + " elements, more than the limit of " +
                     std::to_string(3 * std::uint64_t(kMaxMeshTriangles)));
            const std::uint64_t elem = std::uint64_t(csize) * std::uint64_t(n);
            if (a.bufferView >= 0) {
                check_in_view(a.bufferView, a.byteOffset, a.count, elem, where);
            } else {
                unbacked += a.count * elem;
                if (unbacked > unbacked_limit)
                    fail(where + ": accessors without a buffer view claim " + std::to_string(unbacked) +
                         " bytes, more than 16 x the file's size");
            }
            if (!a.sparse.isSparse) continue;
            const std::string sw = where + " sparse";
            if (a.sparse.count < 0 || std::size_t(a.sparse.count) > a.count)
                fail(sw + " count " + std::to_string(a.sparse.count) + " is not within the accessor's " +
                     std::to_string(a.count));
            const int ic = a.sparse.indices.componentType;
            const int isize = ic == 5121 ? 1 : ic == 5123 ? 2 : ic == 5125 ? 4 : 0;
            if (isize == 0) fail(sw + " indices componentType " + std::to_string(ic) + " is not an index type");
            if (a.sparse.indices.byteOffset < 0 || a.sparse.values.byteOffset < 0) fail(sw + " has a negative byteOffset");
            check_in_view(a.sparse.indices.bufferView, std::size_t(a.sparse.indices.byteOffset),
                          std::uint64_t(a.sparse.count), std::uint64_t(isize), sw + " indices");
            check_in_view(a.sparse.values.bufferView, std::size_t(a.sparse.values.byteOffset),
                          std::uint64_t(a.sparse.count), elem, sw + " values");
        }
    }

    // The bytes of element `i` of accessor `a` at `at` (inside its view and buffer: checked above).
    const unsigned char* at_element(int bufferView, std::size_t offset, std::uint64_t elem, std::size_t i) const {
        const tinygltf::BufferView& v = m.bufferViews[std::size_t(bufferView)];
        const std::uint64_t stride = std::max<std::uint64_t>(v.byteStride, elem);
        return m.buffers[std::size_t(v.buffer)].data.data() + v.byteOffset + offset + i * stride;
    }
    static double component(const unsigned char* p, int type, bool normalized) {
        switch (type) {
            case 5120: { std::int8_t x; std::memcpy(&x, p, 1); return normalized ? std::max(x / 127.0, -1.0) : x; }
            case 5121: return normalized ? p[0] / 255.0 : p[0];
            case 5122: { std::int16_t x; std::memcpy(&x, p, 2); return normalized ? std::max(x / 32767.0, -1.0) : x; }
            case 5123: { std::uint16_t x; std::memcpy(&x, p, 2); return normalized ? x / 65535.0 : x; }
            case 5125: { std::uint32_t x; std::memcpy(&x, p, 4); return x; }
            default: { float x; std::memcpy(&x, p, 4); return x; }
        }
    }
    // Accessor `index` as `n`-component values (`n` <= its type's), the sparse substitutions applied; integers
    // normalized when `normalize` (colours) or the accessor says so.
    std::vector<double> values(int index, int n, bool normalize = false) const {
        const tinygltf::Accessor& a = m.accessors[std::size_t(index)];
        const bool normalized = normalize || a.normalized;
        const int csize = tinygltf::GetComponentSizeInBytes(std::uint32_t(a.componentType));
        const int have = tinygltf::GetNumComponentsInType(std::uint32_t(a.type));
        const std::uint64_t elem = std::uint64_t(csize) * std::uint64_t(have);
        std::vector<double> out(a.count * std::size_t(n), 0.0);
        auto put = [&](std::size_t i, const unsigned char* p) {
            for (int c = 0; c < n && c < have; ++c)
                out[i * std::size_t(n) + std::size_t(c)] = component(p + c * csize, a.componentType, normalized);
        };
        if (a.bufferView >= 0)
            for (std::size_t i = 0; i < a.count; ++i) put(i, at_element(a.bufferView, a.byteOffset, elem, i));
        if (a.sparse.isSparse) {
            const int ic = a.sparse.indices.componentType;
            const std::uint64_t isize = ic == 5121 ? 1 : ic == 5123 ? 2 : 4;
            for (std::size_t k = 0; k < std::size_t(a.sparse.count); ++k) {
                const auto i = std::size_t(component(
                    at_element(a.sparse.indices.bufferView, std::size_t(a.sparse.indices.byteOffset), isize, k), ic, false));
                if (i >= a.count)
                    fail("glTF accessor " + std::to_string(index) + " sparse index " + std::to_string(i) +
                         " is out of range (" + std::to_string(a.count) + " elements)");
                put(i, at_element(a.sparse.values.bufferView, std::size_t(a.sparse.values.byteOffset), elem, k));
            }
        }
        return out;
    }

    MeshPart primitive(const tinygltf::Primitive& p, const std::string& where) const {
        MeshPart part;
        auto attribute = [&](const char* key, int n, bool float_only) -> std::vector<double> {
            const auto it = p.attributes.find(key);
            if (it == p.attributes.end()) return {};
            const tinygltf::Accessor& a = m.accessors[std::size_t(it->second)];
            const int have = tinygltf::GetNumComponentsInType(std::uint32_t(a.type));
            // Colours of unsigned bytes or shorts are normalized (glTF requires the flag; a file without it is read
            // as the specification means it, as before).
            const bool ok_type = a.componentType == 5126 || (!float_only && (a.componentType == 5121 || a.componentType == 5123));
            if (!ok_type || have < n || have > 4)
                fail(where + " " + key + " (accessor " + std::to_string(it->second) + ") is not of a type read here "
                     "(componentType " + std::to_string(a.componentType) + ", " + std::to_string(have) + " components)");
            return values(it->second, n, !float_only);
        };
        const std::vector<double> pos = attribute("POSITION", 3, true), nrm = attribute("NORMAL", 3, true),
                                  col = attribute("COLOR_0", 3, false);
        std::vector<double> uv;
        if (p.attributes.count("TEXCOORD_0") && m.accessors[std::size_t(p.attributes.at("TEXCOORD_0"))].componentType == 5126)
            uv = attribute("TEXCOORD_0", 2, true);
        const std::size_t nv = pos.size() / 3;
        for (std::size_t i = 0; i < nv; ++i) {
            const std::string vw = where + " vertex " + std::to_string(i);
            part.positions.emplace_back(float(pos[3 * i]), float(pos[3 * i + 1]), float(pos[3 * i + 2]));
            if (!finite(part.positions.back())) fail(vw + ": position is not finite");
            if (!nrm.empty()) part.normals.emplace_back(float(nrm[3 * i]), float(nrm[3 * i + 1]), float(nrm[3 * i + 2]));
            if (!nrm.empty() && !finite(part.normals.back())) fail(vw + ": normal is not finite");
            if (!col.empty()) part.colours.emplace_back(float(col[3 * i]), float(col[3 * i + 1]), float(col[3 * i + 2]));
            if (!col.empty() && !finite(part.colours.back())) fail(vw + ": colour is not finite");
            if (!uv.empty()) part.texcoords.emplace_back(float(uv[2 * i]), float(uv[2 * i + 1]));
        }
        std::vector<std::uint32_t> idx;
        if (p.indices >= 0) {
            const tinygltf::Accessor& a = m.accessors[std::size_t(p.indices)];
            if (!(a.componentType == 5121 || a.componentType == 5123 || a.componentType == 5125) ||
                a.type != TINYGLTF_TYPE_SCALAR)
                fail(where + " indices accessor " + std::to_string(p.indices) + " is not of unsigned integer scalars");
            const std::vector<double> v = values(p.indices, 1);
            for (std::size_t i = 0; i < v.size(); ++i) {
                if (v[i] >= double(nv))
                    fail(where + " index " + std::to_string(i) + " is vertex " + mesh_number(v[i]) + ", out of range (" +
                         std::to_string(nv) + " vertices)");
                idx.push_back(std::uint32_t(v[i]));
            }
        } else {
            for (std::size_t i = 0; i < nv; ++i) idx.push_back(std::uint32_t(i));
        }
        const std::size_t n = idx.size();
        auto triangle = [&](std::size_t a, std::size_t b, std::size_t c) {
            part.corners.insert(part.corners.end(), {idx[a], idx[b], idx[c]});
            part.sizes.push_back(3);
        };
        switch (p.mode) {
            case 0: part.dropped_primitives = n; break;                       // points
            case 1: part.dropped_primitives = n / 2; break;                   // lines
            case 2: part.dropped_primitives = n; break;                       // line loop
            case 3: part.dropped_primitives = n > 0 ? n - 1 : 0; break;       // line strip
            case 4:
                for (std::size_t i = 0; i + 2 < n; i += 3) triangle(i, i + 1, i + 2);  // (1 or 2 left over: ignored)
                break;
            case 5:  // strip: every other triangle reversed, so all face one way
                for (std::size_t i = 0; i + 2 < n; ++i) i % 2 ? triangle(i + 1, i, i + 2) : triangle(i, i + 1, i + 2);
                break;
            default:  // 6: fan
                for (std::size_t i = 0; i + 2 < n; ++i) triangle(0, i + 1, i + 2);
        }
        return part;
    }
};

glm::mat4 gltf_local_transform(const tinygltf::Node& node, const std::string& where, const GltfReader& r) {
    auto floats = [&](const std::vector<double>& v, std::size_t n, const char* what) {
        if (!v.empty() && v.size() != n) r.fail(where + " " + what + " is not " + std::to_string(n) + " numbers");
        std::vector<float> f(v.begin(), v.end());
        return f;
    };
    glm::mat4 m(1.0f);
    const std::vector<float> matrix = floats(node.matrix, 16, "matrix");
    if (!matrix.empty()) {
        std::memcpy(&m[0][0], matrix.data(), 64);  // column-major, as glm
        return m;
    }
    const std::vector<float> t = floats(node.translation, 3, "translation"), q = floats(node.rotation, 4, "rotation"),
                             s = floats(node.scale, 3, "scale");
    if (!t.empty()) m = m * glm::translate(glm::mat4(1.0f), glm::vec3(t[0], t[1], t[2]));
    if (!q.empty()) m = m * glm::mat4(glm::mat3_cast(glm::quat(q[3], q[0], q[1], q[2])));  // glTF: x, y, z, w
    if (!s.empty()) m = m * glm::scale(glm::mat4(1.0f), glm::vec3(s[0], s[1], s[2]));
    return m;
}

}  // namespace

MeshFile read_gltf(const std::string& b, const std::string& name, bool binary, MeshSidecars& sidecars) {
    auto fail = [&](const std::string& what) { mesh_fail(name, what); };
    // The container first: a GLB's chunks inside the file, so that tinygltf is handed only consistent lengths.
    std::string_view json(b);
    if (binary) {
        if (b.size() < 20 || b.compare(0, 4, "glTF") != 0) fail("not a GLB file (no \"glTF\" header)");
        if (glb_u32(b, 4) != 2) fail("GLB version " + std::to_string(glb_u32(b, 4)) + " (only 2 is glTF 2.0)");
        const std::uint64_t length = glb_u32(b, 8), json_len = glb_u32(b, 12);
        if (length < 20) fail("GLB header length " + std::to_string(length) + " is shorter than its headers");
        if (length > b.size())
            fail("GLB header length " + std::to_string(length) + " is beyond the file's " + std::to_string(b.size()) +
                 " bytes (truncated)");
        if (glb_u32(b, 16) != 0x4E4F534Au) fail("GLB: the first chunk is not JSON");
        if (json_len > length - 20) fail("GLB JSON chunk of " + std::to_string(json_len) + " bytes runs past the file");
        json = json.substr(20, json_len);
        const std::uint64_t next = 20 + json_len;
        if (next != length) {
            if (next % 4 != 0 || next + 8 > length) fail("GLB: bytes after the JSON chunk are no chunk");
            const std::uint64_t bin = glb_u32(b, std::size_t(next));
            if (bin > length - next - 8)
                fail("GLB BIN chunk of " + std::to_string(bin) + " bytes runs past the file (truncated)");
        }
    }
    int depth = 0;  // JSON nesting, brackets outside strings
    bool in_string = false;
    for (std::size_t i = 0; i < json.size(); ++i) {
        const char c = json[i];
        if (in_string) {
            if (c == '\\') ++i;
            else if (c == '"') in_string = false;
        } else if (c == '"') {
            in_string = true;
        } else if ((c == '[' || c == '{') && ++depth > 2 * kMaxGltfDepth) {
            fail("glTF JSON nested deeper than " + std::to_string(2 * kMaxGltfDepth));
        } else if (c == ']' || c == '}') {
            --depth;
        }
    }
    if (b.size() > std::numeric_limits<unsigned int>::max()) fail("a glTF of 4 GiB or more");

    tinygltf::TinyGLTF loader;
    GltfFiles files{&sidecars, name, std::filesystem::path(name).parent_path().string(), {}};
    if (!files.base.empty()) files.base += '/';
    loader.SetFsCallbacks({gltf_file_exists, gltf_expand_path, gltf_read_file, gltf_write_file, &files});
    loader.SetImageLoader(gltf_skip_image, nullptr);
    tinygltf::Model model;
    std::string err, warn;
    const std::string base = files.base.empty() ? std::string() : files.base.substr(0, files.base.size() - 1);
    const bool ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn,
                                                         reinterpret_cast<const unsigned char*>(b.data()),
                                                         static_cast<unsigned int>(b.size()), base)
                           : loader.LoadASCIIFromString(&model, &err, &warn, b.data(),
                                                        static_cast<unsigned int>(b.size()), base);
    if (!files.error.empty()) throw InputError(files.error);
    if (!ok) {
        const std::string first = err.substr(0, err.find('\n'));
        fail(first.find("parse") != std::string::npos || first.find("JSON") != std::string::npos
                 ? "glTF JSON does not parse (" + mesh_printable(first) + ")"
                 : "glTF: " + mesh_printable(first.empty() ? "not read" : first));
    }
    if (model.asset.version.compare(0, 2, "2.") != 0) fail("not glTF 2.0 (asset.version is not \"2.x\")");
    const GltfReader r{model, name, b.size()};
    r.check_structure(binary);

    MeshFile out;
    out.format = MeshFormat::Gltf;
    out.default_material = {true, glm::vec3(1.0f), glm::vec3(0.0f)};  // glTF's: base colour 1, no emission
    for (std::size_t i = 0; i < model.materials.size(); ++i) {
        const tinygltf::Material& mat = model.materials[i];
        const std::string where = "material " + std::to_string(i);
        double strength = 1.0;
        const auto ext = mat.extensions.find("KHR_materials_emissive_strength");
        if (ext != mat.extensions.end() && ext->second.IsObject() && ext->second.Has("emissiveStrength")) {
            const tinygltf::Value& v = ext->second.Get("emissiveStrength");
            const std::string sw = "glTF material " + std::to_string(i) + " KHR_materials_emissive_strength";
            if (!v.IsNumber()) fail(sw + " emissiveStrength is not a number");
            strength = v.GetNumberAsDouble();
            if (!(strength >= 0.0 && strength <= double(FLT_MAX)))  // also false for NaN
                fail(sw + " emissiveStrength " + mesh_number(strength) + " is not a finite number >= 0");
            strength = double(float(strength));
        }
        const std::vector<double>& base = mat.pbrMetallicRoughness.baseColorFactor;
        const std::vector<double>& em = mat.emissiveFactor;
        if (base.size() != 4 || em.size() != 3) fail("glTF " + where + ": baseColorFactor or emissiveFactor of the wrong size");
        const glm::vec3 albedo{float(base[0]), float(base[1]), float(base[2])};
        check_colour(name, where + " base colour", albedo);
        out.materials.push_back({true, albedo, checked_emission(name, where, glm::vec3(float(em[0]), float(em[1]),
                                                                                     float(em[2])), strength)});
    }
    // Primitives: checked, each read once however many nodes place it; all of them together within the limits before
    // any is read (many primitives may name one large accessor).
    std::uint64_t all_vertices = 0, all_indices = 0;
    for (const tinygltf::Mesh& mesh : model.meshes)
        for (const tinygltf::Primitive& p : mesh.primitives) {
            const auto pos = p.attributes.find("POSITION");
            if (pos != p.attributes.end() && pos->second >= 0 && std::size_t(pos->second) < model.accessors.size())
                all_vertices += model.accessors[std::size_t(pos->second)].count;
            if (p.indices >= 0 && std::size_t(p.indices) < model.accessors.size())
                all_indices += model.accessors[std::size_t(p.indices)].count;
        }
    if (all_vertices > kMaxMeshVertices || all_indices > 3 * std::uint64_t(kMaxMeshTriangles))
        fail("glTF primitives hold " + std::to_string(all_vertices) + " vertices and " + std::to_string(all_indices) +
             " indices in all, more than the limits of " + std::to_string(kMaxMeshVertices) + " and " +
             std::to_string(3 * std::uint64_t(kMaxMeshTriangles)));
    std::vector<std::vector<std::size_t>> part_of(model.meshes.size());
    for (std::size_t i = 0; i < model.meshes.size(); ++i)
        for (std::size_t k = 0; k < model.meshes[i].primitives.size(); ++k) {
            const tinygltf::Primitive& p = model.meshes[i].primitives[k];
            const std::string pw = "glTF mesh " + std::to_string(i) + " primitive " + std::to_string(k);
            if (p.extensions.count("KHR_draco_mesh_compression"))
                fail(pw + " is Draco-compressed (KHR_draco_mesh_compression), which is not read: decompress it first");
            const auto pos = p.attributes.find("POSITION");
            if (pos == p.attributes.end()) fail(pw + " has no POSITION");
            for (const auto& [key, a] : p.attributes) r.check_index(a, model.accessors.size(), pw + " " + key, "accessors");
            const std::size_t vertices = model.accessors[std::size_t(pos->second)].count;
            // Every attribute holds one element per vertex (glTF 2.0 3.7.2.1).
            for (const auto& [key, a] : p.attributes)
                if (model.accessors[std::size_t(a)].count != vertices)
                    fail(pw + " attribute " + key + " has " + std::to_string(model.accessors[std::size_t(a)].count) +
                         " elements for " + std::to_string(vertices) + " vertices");
            if (p.mode < 0 || p.mode > 6) fail(pw + " mode is not a glTF primitive mode (0..6)");
            if (p.indices >= 0) r.check_index(p.indices, model.accessors.size(), pw + " indices", "accessors");
            if (p.material >= 0) r.check_index(p.material, model.materials.size(), pw + " material", "materials");
            part_of[i].push_back(out.parts.size());
            out.parts.push_back(r.primitive(p, pw));
            out.parts.back().material = p.material;
        }
    // Nodes: a forest at most kMaxGltfDepth deep (checked without recursion).
    std::vector<int> parent(model.nodes.size(), -1);
    for (std::size_t i = 0; i < model.nodes.size(); ++i) {
        const std::string where = "glTF node " + std::to_string(i);
        if (model.nodes[i].mesh >= 0) r.check_index(model.nodes[i].mesh, model.meshes.size(), where + " mesh", "meshes");
        for (const int c : model.nodes[i].children) {
            r.check_index(c, model.nodes.size(), where + " child", "nodes");
            if (parent[std::size_t(c)] >= 0 || std::size_t(c) == i)
                fail("glTF node " + std::to_string(c) + " has two parents (nodes " +
                     std::to_string(parent[std::size_t(c)] < 0 ? i : std::size_t(parent[std::size_t(c)])) + " and " +
                     std::to_string(i) + "): the node graph is not a tree");
            parent[std::size_t(c)] = int(i);
        }
    }
    for (std::size_t i = 0; i < model.nodes.size(); ++i) {  // depth by walking up: a cycle shows as a path too long
        int d = 0;
        for (int k = int(i); k >= 0; k = parent[std::size_t(k)])
            if (++d > kMaxGltfDepth)
                fail("glTF node " + std::to_string(i) + " is more than " + std::to_string(kMaxGltfDepth) +
                     " levels deep (or in a cycle)");
    }
    // The default scene (else the first): its nodes depth-first, each node's primitives before its children's.
    if (model.scenes.empty()) fail("glTF has no scene (nothing to place)");
    const int scene = model.defaultScene >= 0 ? model.defaultScene : 0;
    r.check_index(scene, model.scenes.size(), "glTF scene", "scenes");
    std::vector<std::pair<int, glm::mat4>> stack;
    const std::vector<int>& roots = model.scenes[std::size_t(scene)].nodes;
    for (auto it = roots.rbegin(); it != roots.rend(); ++it) {
        r.check_index(*it, model.nodes.size(), "glTF scene node", "nodes");
        stack.push_back({*it, glm::mat4(1.0f)});
    }
    // A node may be listed as a root more than once: the walk is bounded (a placement per node visit at most).
    constexpr std::size_t kMaxGltfVisits = std::size_t(1) << 20;
    std::size_t visits = 0;
    while (!stack.empty()) {
        const auto [k, parent_xf] = stack.back();
        stack.pop_back();
        if (++visits > kMaxGltfVisits)
            fail("glTF scene " + std::to_string(scene) + " places more than " + std::to_string(kMaxGltfVisits) + " nodes");
        const tinygltf::Node& node = model.nodes[std::size_t(k)];
        const glm::mat4 xf = parent_xf * gltf_local_transform(node, "glTF node " + std::to_string(k), r);
        if (node.mesh >= 0)
            for (const std::size_t part : part_of[std::size_t(node.mesh)]) out.instances.push_back({part, xf});
        for (auto it = node.children.rbegin(); it != node.children.rend(); ++it) stack.push_back({*it, xf});
    }
    return out;
}

}  // namespace ngi::detail
