// Triangle meshes (issue 27, the input side): the mesh basics of ngi/mesh.hpp, OBJ / PLY / glTF files written here
// and loaded through their readers (counts, normals, colours, transforms), bad and hostile files refused with an
// InputError naming the file (quickly: a 1 KB file claiming 10^9 faces must not allocate for them), the procedural
// mesh families (deterministic, closed, outward, inside their grid), the scene specs and the camera orbit around
// a mesh.
#include <sys/stat.h>

#include <catch2/catch.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "io_test_support.hpp"
#include "ngi/camera_path.hpp"
#include "ngi/error.hpp"
#include "ngi/mesh.hpp"
#include "ngi/scene.hpp"
#include "ngi/host_memory.hpp"
#include "render/bvh.hpp"
#include "render/mesh_scene.hpp"

using namespace ngi;
using Catch::Matchers::Contains;
using ngi::test::spit;

namespace {

float srgb(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

glm::vec3 geometric_normal(const TriangleMesh& m, std::size_t i) {
    const glm::uvec3 t = m.triangles[i];
    return glm::cross(m.positions[t.y] - m.positions[t.x], m.positions[t.z] - m.positions[t.x]);
}

// The InputError message of load_mesh(path) (or parse_mesh of `bytes` when given), "" if it loaded; `seconds`
// gets the wall time it took.
std::string mesh_error(const std::string& path, double* seconds = nullptr) {
    const auto t0 = std::chrono::steady_clock::now();
    std::string e;
    try {
        load_mesh(path);
    } catch (const InputError& x) {
        e = x.what();
    }
    if (seconds) *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return e;
}

// A unit cube as six quads (outward, counter-clockwise), the first three faces in material "red", the others in
// "glow"; the .mtl beside it.
const char* kCubeObj = R"(# a cube
mtllib cube.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
usemtl red
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
usemtl glow
f 4 8 7 3
f 1 5 8 4
f 2 3 7 6
f 1 2 2
)";
const char* kCubeMtl = "newmtl red\nKd 0.5 0.2 0.1\nnewmtl glow\nKd 1 1 1\nKe 2 1 0.5\n";

const char* kPlyHeaderColours = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                                "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                                "element face 2\nproperty list uchar int vertex_indices\nend_header\n";

template <class T>
void put(std::string& b, T v, bool big = false) {
    char c[sizeof(T)];
    std::memcpy(c, &v, sizeof(T));
    if (big) std::reverse(c, c + sizeof(T));
    b.append(c, sizeof(T));
}

// A binary PLY quad (two triangles) with normals: 4 vertices (x y z nx ny nz floats), 2 faces (uchar count, int
// indices).
std::string binary_ply(bool big, const std::string& face_count = "2") {
    std::string b = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                    "property float nx\nproperty float ny\nproperty float nz\nelement face " + face_count +
                    "\nproperty list uchar int vertex_indices\nend_header\n";
    const float v[4][3] = {{0, 0, 0}, {2, 0, 0}, {2, 0, 2}, {0, 0, 2}};
    for (const auto& p : v) {
        for (float x : p) put(b, x, big);
        for (float x : {0.0f, 0.0f, -3.0f}) put(b, x, big);  // not unit in the file: normalized on load
    }
    for (const glm::ivec3 f : {glm::ivec3(0, 1, 2), glm::ivec3(0, 2, 3)}) {
        put(b, std::uint8_t(3));
        for (int k = 0; k < 3; ++k) put(b, std::int32_t(f[k]), big);
    }
    return b;
}

std::string base64(const std::string& in) {
    static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (std::size_t i = 0; i < in.size(); i += 3) {
        std::uint32_t n = std::uint32_t(std::uint8_t(in[i])) << 16;
        if (i + 1 < in.size()) n |= std::uint32_t(std::uint8_t(in[i + 1])) << 8;
        if (i + 2 < in.size()) n |= std::uint8_t(in[i + 2]);
        out += t[n >> 18 & 63];
        out += t[n >> 12 & 63];
        out += i + 1 < in.size() ? t[n >> 6 & 63] : '=';
        out += i + 2 < in.size() ? t[n & 63] : '=';
    }
    return out;
}

// A glTF quad (positions, normals +z, COLOR_0, 6 indices) under two nodes: translated and scaled by 2, and
// mirrored in x. Returns {json, bin}; `glb` leaves the buffer's uri out (the GLB's BIN chunk holds it).
std::pair<nlohmann::json, std::string> gltf_quad(bool glb) {
    std::string bin;
    const float pos[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    for (const auto& p : pos) for (float x : p) put(bin, x);
    for (int i = 0; i < 4; ++i) for (float x : {0.0f, 0.0f, 1.0f}) put(bin, x);
    for (int i = 0; i < 4; ++i) for (float x : {1.0f, 0.5f, 1.0f}) put(bin, x);  // COLOR_0 (linear)
    for (std::uint16_t i : {0, 1, 2, 0, 2, 3}) put(bin, i);
    nlohmann::json j = {
        {"asset", {{"version", "2.0"}}},
        {"scene", 0},
        {"scenes", {{{"nodes", {0, 1}}}}},
        {"nodes", {{{"mesh", 0}, {"translation", {10, 0, 0}}, {"scale", {2, 2, 2}}},
                   {{"mesh", 0}, {"scale", {-1, 1, 1}}}}},
        {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}, {"COLOR_0", 2}}},
                                      {"indices", 3}, {"material", 0}}}}}}},
        {"materials", {{{"pbrMetallicRoughness", {{"baseColorFactor", {0.5, 0.3, 1.0, 1.0}}}},
                        {"emissiveFactor", {1.0, 0.5, 0.0}}}}},
        {"buffers", {{{"byteLength", bin.size()}}}},
        {"bufferViews", {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 48}},
                         {{"buffer", 0}, {"byteOffset", 48}, {"byteLength", 48}},
                         {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 48}},
                         {{"buffer", 0}, {"byteOffset", 144}, {"byteLength", 12}}}},
        {"accessors", {{{"bufferView", 0}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"},
                        {"min", {0, 0, 0}}, {"max", {1, 1, 0}}},
                       {{"bufferView", 1}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}},
                       {{"bufferView", 2}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}},
                       {{"bufferView", 3}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}}}}};
    if (!glb) j["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(bin);
    return {j, bin};
}

std::string glb_file(const nlohmann::json& j, std::string bin) {
    std::string js = j.dump();
    while (js.size() % 4) js += ' ';
    while (bin.size() % 4) bin += '\0';
    std::string b = "glTF";
    put(b, std::uint32_t(2));
    put(b, std::uint32_t(12 + 8 + js.size() + 8 + bin.size()));
    put(b, std::uint32_t(js.size()));
    put(b, std::uint32_t(0x4E4F534A));
    b += js;
    put(b, std::uint32_t(bin.size()));
    put(b, std::uint32_t(0x004E4942));
    return b + bin;
}

// Every undirected edge used by exactly two triangles, once in each direction: closed and consistently oriented.
bool closed_and_oriented(const TriangleMesh& m) {
    std::vector<std::uint64_t> directed;
    directed.reserve(m.triangles.size() * 3);
    for (const auto& t : m.triangles)
        for (int k = 0; k < 3; ++k) directed.push_back(std::uint64_t(t[k]) << 32 | t[(k + 1) % 3]);
    std::sort(directed.begin(), directed.end());
    if (std::adjacent_find(directed.begin(), directed.end()) != directed.end()) return false;  // a directed edge twice
    for (std::uint64_t e : directed) {
        const std::uint64_t rev = (e & 0xffffffffu) << 32 | e >> 32;
        if (!std::binary_search(directed.begin(), directed.end(), rev)) return false;
    }
    return true;
}

}  // namespace

TEST_CASE("mesh basics: bounds, area-weighted normals, validation naming the element", "[mesh]") {
    TriangleMesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {9, 9, 9}};  // the last one is used by nothing
    m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};              // a tetrahedron, outward
    m.materials.assign(4, 1);
    const auto [lo, hi] = mesh_bounds(m);
    CHECK(lo == glm::vec3(0.0f));
    CHECK(hi == glm::vec3(1.0f));
    compute_vertex_normals(m);
    REQUIRE(m.normals.size() == 5);
    // Vertex 0 touches three faces of area 1/2 (normals -x, -y, -z): their sum is (-1, -1, -1) / 2.
    CHECK(glm::length(m.normals[0] - glm::normalize(glm::vec3(-1))) < 1e-6f);
    CHECK(m.normals[4] == glm::vec3(0, 1, 0));  // unused: +y
    CHECK_NOTHROW(validate_mesh(m, 2, "tet"));

    auto error = [&](TriangleMesh bad, std::size_t palette = 2) {
        try {
            validate_mesh(bad, palette, "tet");
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    TriangleMesh b = m;
    b.positions[3].y = NAN;
    CHECK_THAT(error(b), Contains("mesh tet") && Contains("vertex 3 position"));
    b = m;
    b.normals[2] = glm::vec3(INFINITY, 0, 0);
    CHECK_THAT(error(b), Contains("vertex 2 normal"));
    b = m;
    b.triangles[1].z = 5;
    CHECK_THAT(error(b), Contains("triangle 1 vertex index 5 is out of range"));
    b = m;
    b.materials[2] = 0;
    CHECK_THAT(error(b), Contains("triangle 2 material 0 is air"));
    CHECK_THAT(error(m, 1), Contains("triangle 0 material 1 is outside the palette of 1"));
    CHECK_THAT(error(TriangleMesh{}), Contains("has no triangles"));

    CHECK(is_mesh_path("a/b.OBJ"));
    CHECK(is_mesh_path("x.glb"));
    CHECK(is_mesh_path("x.gltf"));
    CHECK(is_mesh_path("x.ply"));
    CHECK_FALSE(is_mesh_path("x.vox"));
    CHECK_FALSE(is_mesh_path("knot:seed=1"));
}

TEST_CASE("OBJ: quads triangulated, .mtl colours sRGB -> linear, emission, degenerate faces dropped", "[mesh]") {
    test::TempDir dir("mesh-obj");
    spit(dir / "cube.obj", kCubeObj);
    spit(dir / "cube.mtl", kCubeMtl);
    const LoadedMesh l = load_mesh(dir / "cube.obj");
    const TriangleMesh& m = l.mesh;
    CHECK(m.triangle_count() == 12);
    CHECK(l.dropped_degenerate == 1);  // "f 1 2 2"
    REQUIRE(l.materials.size() == 2);
    CHECK(l.materials[0].albedo.x == Approx(srgb(0.5f)));
    CHECK(l.materials[0].albedo.y == Approx(srgb(0.2f)));
    CHECK(l.materials[0].albedo.z == Approx(srgb(0.1f)));
    CHECK(l.materials[0].emission == glm::vec3(0.0f));
    CHECK(l.materials[1].albedo == glm::vec3(0.95f));  // Kd 1 capped like every scene's albedo
    CHECK(l.materials[1].emission == glm::vec3(2.0f, 1.0f, 0.5f));
    for (std::size_t i = 0; i < 12; ++i) CHECK(m.materials[i] == (i < 6 ? 1 : 2));
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        CHECK(std::abs(glm::length(m.normals[i]) - 1.0f) < 1e-5f);
        CHECK(glm::dot(m.normals[i], m.positions[i] - glm::vec3(0.5f)) > 0.0f);  // outward at the corners
    }
    for (std::size_t i = 0; i < 12; ++i) {  // counter-clockwise from outside, as written
        const glm::uvec3 t = m.triangles[i];
        const glm::vec3 c = (m.positions[t.x] + m.positions[t.y] + m.positions[t.z]) / 3.0f;
        CHECK(glm::dot(geometric_normal(m, i), c - glm::vec3(0.5f)) > 0.0f);
    }
    // parse_mesh reads the bytes alone: the same geometry, without the .mtl's colours.
    const LoadedMesh p = parse_mesh(kCubeObj, "cube.obj");
    CHECK(p.mesh.triangles.size() == 12);
    REQUIRE(p.materials.size() == 1);
    CHECK(p.materials[0].albedo == Material{}.albedo);

    // Without material colours, vertex colours (sRGB) give each triangle the mean of its corners.
    const LoadedMesh v = parse_mesh("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nv 1 1 0 1 1 1\nf 1 2 3\nf 2 4 3\n",
                                    "colours.obj");
    REQUIRE(v.mesh.triangle_count() == 2);
    REQUIRE(v.materials.size() == 2);
    CHECK(v.materials[v.mesh.materials[0] - 1].albedo.x == Approx(1.0f / 3.0f));
    CHECK(v.materials[v.mesh.materials[1] - 1].albedo.y == Approx(2.0f / 3.0f));
}

TEST_CASE("PLY: ASCII with vertex colours, binary (both byte orders) with normals", "[mesh]") {
    const std::string ascii = std::string(kPlyHeaderColours) +
                              "0 0 0 255 0 0\n1 0 0 0 255 0\n1 1 0 0 0 255\n0 1 0 128 128 128\n3 0 1 2\n3 0 2 3\n";
    const LoadedMesh a = parse_mesh(ascii, "colours.ply");
    REQUIRE(a.mesh.triangle_count() == 2);
    CHECK(a.mesh.positions.size() == 4);
    const Material& m0 = a.materials[a.mesh.materials[0] - 1];
    CHECK(m0.albedo.x == Approx(1.0f / 3.0f));
    CHECK(m0.albedo.y == Approx(1.0f / 3.0f));
    const Material& m1 = a.materials[a.mesh.materials[1] - 1];
    CHECK(m1.albedo.x == Approx((1.0f + srgb(128.0f / 255.0f)) / 3.0f).epsilon(1e-4));
    for (const glm::vec3& n : a.mesh.normals) CHECK(glm::length(n - glm::vec3(0, 0, 1)) < 1e-6f);  // computed: +z

    for (const bool big : {false, true}) {
        const LoadedMesh b = parse_mesh(binary_ply(big), "quad.ply");
        REQUIRE(b.mesh.triangle_count() == 2);
        CHECK(b.mesh.positions.size() == 4);
        CHECK(mesh_bounds(b.mesh).second == glm::vec3(2, 0, 2));
        for (const glm::vec3& n : b.mesh.normals) CHECK(n == glm::vec3(0, 0, -1));  // the file's, normalized
        REQUIRE(b.materials.size() == 1);
        CHECK(b.materials[0].albedo == Material{}.albedo);  // no colour anywhere: ngi's default
    }
}

TEST_CASE("PLY: more distinct vertex colours than the palette holds are merged into 255 materials", "[mesh]") {
    // 1,000 triangles, each a different grey: binned on a grid in sRGB, every triangle's albedo stays near its own.
    const int n = 1000;
    std::string b = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(3 * n) +
                    "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar "
                    "green\nproperty uchar blue\nelement face " + std::to_string(n) +
                    "\nproperty list uchar int vertex_indices\nend_header\n";
    for (int i = 0; i < n; ++i) {
        const int g = i * 255 / (n - 1), r = (i * 7) % 256;
        for (int k = 0; k < 3; ++k)
            b += std::to_string(i + (k == 1)) + " " + std::to_string(k == 2) + " 0 " + std::to_string(r) + " " +
                 std::to_string(g) + " " + std::to_string(g) + "\n";
    }
    for (int i = 0; i < n; ++i)
        b += "3 " + std::to_string(3 * i) + " " + std::to_string(3 * i + 1) + " " + std::to_string(3 * i + 2) + "\n";
    const LoadedMesh l = parse_mesh(b, "greys.ply");
    REQUIRE(l.mesh.triangle_count() == std::size_t(n));
    CHECK(l.materials.size() <= 255);
    CHECK(l.materials.size() > 100);
    // The triangle at position i in the file: the mesh keeps the file's triangle order.
    for (int i = 0; i < n; i += 37) {
        const float g = srgb(float(i * 255 / (n - 1)) / 255.0f);
        CHECK(std::abs(l.materials[l.mesh.materials[std::size_t(i)] - 1].albedo.y - std::min(g, 0.95f)) < 0.06f);
    }
}

TEST_CASE("glTF and GLB: node transforms (and a mirror), linear base colour x COLOR_0, emission", "[mesh]") {
    test::TempDir dir("mesh-gltf");
    for (const bool glb : {false, true}) {
        const auto [j, bin] = gltf_quad(glb);
        const std::string path = glb ? dir / "quad.glb" : dir / "quad.gltf";
        spit(path, glb ? glb_file(j, bin) : j.dump());
        const LoadedMesh l = load_mesh(path);
        const TriangleMesh& m = l.mesh;
        REQUIRE(m.triangle_count() == 4);  // the quad under two nodes
        const auto [lo, hi] = mesh_bounds(m);
        CHECK(lo == glm::vec3(-1, 0, 0));   // the mirrored copy
        CHECK(hi == glm::vec3(12, 2, 0));   // 2 x + (10, 0, 0)
        REQUIRE(l.materials.size() == 1);
        CHECK(l.materials[0].albedo.x == Approx(0.5f));   // linear in glTF: as written
        CHECK(l.materials[0].albedo.y == Approx(0.15f));  // x COLOR_0's 0.5
        CHECK(l.materials[0].albedo.z == Approx(0.95f));  // capped
        CHECK(l.materials[0].emission == glm::vec3(1.0f, 0.5f, 0.0f));
        for (std::size_t i = 0; i < 4; ++i)  // the mirror flipped the winding back: fronts face the normals
            CHECK(glm::dot(geometric_normal(m, i), m.normals[m.triangles[i].x]) > 0.0f);
        for (const glm::vec3& n : m.normals) CHECK(n == glm::vec3(0, 0, 1));
    }
    // parse_mesh does not read external buffers.
    auto [j, bin] = gltf_quad(true);
    j["buffers"][0]["uri"] = "quad.bin";
    CHECK_THROWS_WITH(parse_mesh(j.dump(), "ext.gltf"), Contains("ext.gltf") && Contains("external buffer 'quad.bin'"));
    spit(dir / "quad.bin", bin);
    spit(dir / "ext.gltf", j.dump());
    CHECK(load_mesh(dir / "ext.gltf").mesh.triangle_count() == 4);  // load_mesh does, beside the file
}

TEST_CASE("mesh materials: glTF emissive strength applied, negative colours, emission past the bound and a missing "
          ".mtl refused", "[mesh]") {
    // Issue 51: KHR_materials_emissive_strength was ignored (the loader of the time did not read it) and 1e30 accepted;
    // negative Kd / baseColor / Ke became 0 and a missing .mtl default grey, silently.
    test::TempDir dir("mesh-materials");
    auto with_material = [&](bool glb, const std::function<void(nlohmann::json&)>& edit) {
        auto [j, bin] = gltf_quad(glb);
        edit(j["materials"][0]);
        const std::string path = glb ? dir / "m.glb" : dir / "m.gltf";
        spit(path, glb ? glb_file(j, bin) : j.dump());
        return path;
    };
    auto strength = [](const nlohmann::json& v) {
        return [v](nlohmann::json& m) { m["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"] = v; };
    };
    for (const bool glb : {false, true}) {
        INFO((glb ? "glb" : "gltf"));
        const LoadedMesh l = load_mesh(with_material(glb, strength(4.0)));
        REQUIRE(l.materials.size() == 1);
        CHECK(l.materials[0].emission == glm::vec3(4.0f, 2.0f, 0.0f));  // emissiveFactor (1, 0.5, 0) x 4
        // The extension without a strength is the extension's default, 1.
        CHECK(load_mesh(with_material(glb, [](nlohmann::json& m) {
                  m["extensions"]["KHR_materials_emissive_strength"] = nlohmann::json::object();
              })).materials[0].emission == glm::vec3(1.0f, 0.5f, 0.0f));
        CHECK_THAT(mesh_error(with_material(glb, strength(1e30))),
                   Contains("m.gl") && Contains("material 0") && Contains("exceeds the bound of 65504"));
        CHECK_THAT(mesh_error(with_material(glb, strength(-1.0))),
                   Contains("glTF material 0 KHR_materials_emissive_strength") && Contains("not a finite number >= 0"));
        CHECK_THAT(mesh_error(with_material(glb, strength("bright"))), Contains("emissiveStrength is not a number"));
        CHECK_THAT(mesh_error(with_material(glb, [](nlohmann::json& m) {
                       m["pbrMetallicRoughness"]["baseColorFactor"] = {0.5, -0.25, 1.0, 1.0};
                   })),
                   Contains("material 0 base colour") && Contains("negative component"));
        CHECK_THAT(mesh_error(with_material(glb, [](nlohmann::json& m) { m["emissiveFactor"] = {-1.0, 0.5, 0.0}; })),
                   Contains("material 0 emissive colour") && Contains("negative component"));
    }
    // An OBJ's .mtl: negative Kd or Ke refused; a library that is not there refused, saying what to do.
    const std::string tri = "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
    spit(dir / "t.obj", tri);
    for (const char* mtl : {"newmtl a\nKd 0.5 -0.1 0.5\n", "newmtl a\nKd 0.5 0.5 0.5\nKe -2 0 0\n"}) {
        INFO(mtl);
        spit(dir / "t.mtl", mtl);
        CHECK_THAT(mesh_error(dir / "t.obj"), Contains("t.obj") && Contains("negative component"));
    }
    // A usemtl of a name the library does not define: its faces would lose their colour, silently (issue 51).
    spit(dir / "t.mtl", "newmtl b\nKd 0.5 0.5 0.5\nnewmtl c d\nKd 1 1 1\n");
    CHECK_THAT(mesh_error(dir / "t.obj"), Contains("t.obj") && Contains("OBJ line 5: usemtl 'a'") &&
                                              Contains("t.mtl defines b, c d") && Contains("lose their colour"));
    // Names are the rest of the line, blanks and a CR trimmed (newmtl and usemtl alike); a name may hold a space.
    spit(dir / "t2.obj", "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl  c d \r\nf 1 2 3\n");
    CHECK(load_mesh(dir / "t2.obj").mesh.triangle_count() == 1);
    std::filesystem::remove(dir / "t.mtl");
    CHECK_THAT(mesh_error(dir / "t.obj"),
               Contains("t.obj") && Contains("material library") && Contains("t.mtl does not exist"));
    // Without the mtllib line it loads in the default colour; parse_mesh reads no library, so it loads too.
    spit(dir / "plain.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    CHECK(load_mesh(dir / "plain.obj").mesh.triangle_count() == 1);
    CHECK(parse_mesh(tri, "t.obj").mesh.triangle_count() == 1);
}

TEST_CASE("mesh: instanced triangles meet the host-memory budget before loading and before the BVH", "[mesh][limits]") {
    // Issue 51: a 400 KB .glb listing one 20,000-triangle primitive under 838 nodes (16.8 M triangles) reached
    // 3.7 GB with NGI_HOST_MEMORY_LIMIT=1G. The same shape, small: one quad under 2,000 nodes = 4,000 triangles.
    struct Limit {
        explicit Limit(std::uint64_t b) { set_host_memory_limit(b); }
        ~Limit() { set_host_memory_limit(0); }
    };
    test::TempDir dir("mesh-instances");
    auto [j, bin] = gltf_quad(true);
    j["nodes"] = nlohmann::json::array();
    j["scenes"][0]["nodes"] = nlohmann::json::array();
    for (int k = 0; k < 2000; ++k) {
        j["nodes"].push_back({{"mesh", 0}, {"translation", {k % 50, k / 50, 0}}});
        j["scenes"][0]["nodes"].push_back(k);
    }
    const std::string path = dir / "many.glb";
    spit(path, glb_file(j, bin));
    const LoadedMesh l = load_mesh(path);  // the default budget holds it
    REQUIRE(l.mesh.triangle_count() == 4000);
    {
        const Limit limit(256 << 10);  // the 79 KB file fits; 4,000 triangles need ~0.7 MB at load and in the BVH
        CHECK_THAT(mesh_error(path), Contains("many.glb") && Contains("4000 triangles") &&
                                         Contains("every node's instance counted") && Contains("host-memory limit"));
        CHECK_THROWS_WITH(detail::build_bvh(l.mesh), Contains("build the BVH of 4000 triangles") &&
                                                         Contains("host-memory limit"));
    }
    CHECK(detail::build_bvh(l.mesh).tri_info.size() == 4 * 4000);
}

TEST_CASE("mesh: a mesh too small to render or too far out for float32 is refused", "[mesh][limits]") {
    // Issue 51: a 0.5 m mesh at 1e7 m collapsed in float32 into an all-sky frame (exit 0); ao-data on a 1e-20 m
    // mesh wrote empty views.
    // x at 1e7 m (floats step by 1 m there; y keeps its precision, so the triangle keeps an area).
    CHECK_THROWS_WITH(parse_mesh("v 1e7 0 0\nv 10000001 0 0\nv 1e7 0.5 0\nf 1 2 3\n", "far.obj"),
                      Contains("far.obj") && Contains("float32 positions step by 1 m") &&
                          Contains("move it near the origin"));
    // The glTF quad (1 m) under one node: translated to 1e7 m, or scaled to 1e-20 m.
    auto [j, bin] = gltf_quad(true);
    j["scenes"][0]["nodes"] = {0};
    j["nodes"][0]["scale"] = {1, 1, 1};
    j["nodes"][0]["translation"] = {1e7, 0, 0};
    CHECK_THROWS_WITH(parse_mesh(glb_file(j, bin), "far.glb"), Contains("far.glb") && Contains("float32"));
    j["nodes"][0]["translation"] = {0, 0, 0};
    j["nodes"][0]["scale"] = {1e-20, 1e-20, 1e-20};
    CHECK_THROWS_WITH(parse_mesh(glb_file(j, bin), "tiny.glb"),
                      Contains("tiny.glb") && Contains("1e-20 m across") && Contains("read as metres"));
    // Large but resolvable: 1 km from the origin (float steps of 6e-5 m), a 1 m mesh loads.
    CHECK(parse_mesh("v 1000 0 0\nv 1001 0 0\nv 1000 1 0\nf 1 2 3\n", "km.obj").mesh.triangle_count() == 1);
}

TEST_CASE("bad mesh files: an InputError naming the file, quickly, for every class", "[mesh]") {
    test::TempDir dir("mesh-bad");
    struct Case {
        std::string name, bytes, expect;
    };
    const std::string ply_head =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    std::string huge_list = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float "
                            "y\nproperty float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n";
    for (int i = 0; i < 9; ++i) put(huge_list, 0.0f);
    put(huge_list, std::uint32_t(0xffffffffu));  // a list of 4e9 indices in a 200-byte file
    put(huge_list, std::int32_t(0));
    auto [gj, gbin] = gltf_quad(false);
    nlohmann::json big_accessor = gj, outside_view = gj, cycle = gj, no_view = gj, bad_index = gj;
    big_accessor["accessors"][3]["count"] = 1000000000;
    outside_view["accessors"][0]["count"] = 5;
    cycle["nodes"][0]["children"] = {1};
    cycle["nodes"][1]["children"] = {0};
    no_view["accessors"][0].erase("bufferView");
    no_view["accessors"][0]["count"] = 50000000;
    std::string bad_idx_bin = gbin;
    bad_idx_bin[bad_idx_bin.size() - 2] = 9;  // index 9 of 4 vertices
    bad_index["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(bad_idx_bin);
    const std::string glb = glb_file(gltf_quad(true).first, gltf_quad(true).second);
    const std::vector<Case> cases = {
        {"empty.obj", "", "is empty"},
        {"no_faces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", "load mesh"},
        {"malformed.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "line 4"},
        {"index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 1000000000\n", "vertex index 1000000000 is out of range"},
        {"relative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", "relative vertex index -4"},
        {"nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "not finite"},
        {"inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1e39 0\nf 1 2 3\n", "not finite"},
        {"degenerate.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "no triangle with an area"},
        {"lines.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nl 1 2\n", "load mesh"},
        {"truncated.ply", ply_head + "0 0 0\n1 0 0\n", "truncated"},
        {"truncated_bin.ply", binary_ply(false).substr(0, binary_ply(false).size() - 5), "truncated"},
        {"no_header_end.ply", "ply\nformat ascii 1.0\nelement vertex 3\n", "end_header"},
        {"claims_1e9.ply", ply_head.substr(0, ply_head.find("element face")) +
                               "element face 1000000000\nproperty list uchar int vertex_indices\nend_header\n",
         "1000000000 elements 'face', more than the limit"},
        {"claims_1e7.ply", binary_ply(false, "10000000"), "truncated, or counts that are not true"},
        {"huge_list.ply", huge_list, "claims 4294967295 items"},
        {"index.ply", ply_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "load mesh"},
        {"nan.ply", ply_head + "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", "not finite"},
        {"empty.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nend_header\n", "load mesh"},
        {"not_json.gltf", "{\"asset\": {\"version\": \"2.0\"}, ", "does not parse"},
        {"version1.gltf", R"({"asset": {"version": "1.0"}})", "not glTF 2.0"},
        {"big_accessor.gltf", big_accessor.dump(), "accessor 3 claims 1000000000 elements"},
        {"outside_view.gltf", outside_view.dump(), "accessor 0: 5 elements need 60 bytes, buffer view 0 has 48"},
        {"cycle.gltf", cycle.dump(), "in a cycle"},
        {"no_view.gltf", no_view.dump(), "more than 16 x the file's size"},
        {"bad_index.gltf", bad_index.dump(), "index 5 is vertex 9, out of range (4 vertices)"},
        {"truncated.glb", glb.substr(0, glb.size() - 10), "truncated"},
        {"deep.gltf", std::string(200, '[') + std::string(200, ']'), "nested deeper"},
    };
    for (const Case& c : cases) {
        INFO(c.name);
        spit(dir / c.name, c.bytes);
        double seconds = 0;
        const std::string e = mesh_error(dir / c.name, &seconds);
        CHECK_THAT(e, Contains(dir / c.name) && Contains(c.expect));
        // Claims are checked before anything is allocated for them: each refusal is immediate (a 10^9-element
        // allocation alone would take seconds and gigabytes).
        CHECK(seconds < 0.5);
        // parse_mesh gives the same refusal from the bytes.
        try {
            parse_mesh(c.bytes, c.name);
            FAIL("parse_mesh loaded " << c.name);
        } catch (const InputError& x) {
            CHECK_THAT(std::string(x.what()), Contains(c.name));
        }
    }
    // Not files: a directory, a FIFO, a device; a missing file; a size over the limit is read_file's (tested there).
    std::filesystem::create_directories(dir / "dir.obj");
    CHECK_THAT(mesh_error(dir / "dir.obj"), Contains("dir.obj") && Contains("directory"));
    REQUIRE(::mkfifo((dir / "fifo.ply").c_str(), 0600) == 0);
    CHECK_THAT(mesh_error(dir / "fifo.ply"), Contains("fifo.ply") && Contains("not a regular file"));
    std::filesystem::create_symlink("/dev/zero", dir / "zero.glb");
    CHECK_THAT(mesh_error(dir / "zero.glb"), Contains("zero.glb"));
    CHECK_THAT(mesh_error(dir / "missing.obj"), Contains("missing.obj"));
    CHECK_THAT(mesh_error(dir / "mesh.stl"), Contains("not a mesh file extension"));
    // An .mtl that is a FIFO is refused like the mesh itself (it would block a reader forever).
    spit(dir / "fifo_mtl.obj", "mtllib fifo.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    REQUIRE(::mkfifo((dir / "fifo.mtl").c_str(), 0600) == 0);
    CHECK_THAT(mesh_error(dir / "fifo_mtl.obj"), Contains("fifo.mtl") && Contains("not a regular file"));
}

TEST_CASE("mesh families: deterministic, closed, outward, smooth, inside their grid", "[mesh]") {
    for (const std::string family : {"knot", "superquadric", "blob"}) {
        for (const std::uint32_t seed : {1u, 2u}) {
            INFO(family << " seed " << seed);
            const LoadedMesh a = detail::generate_mesh_object(family, seed);
            const TriangleMesh& m = a.mesh;
            CHECK(m.triangle_count() >= 20000);
            CHECK(m.triangle_count() <= 100000);
            REQUIRE_NOTHROW(validate_mesh(m, a.materials.size() + 1, family));
            REQUIRE(a.materials.size() == 1);
            CHECK(glm::all(glm::lessThanEqual(a.materials[0].albedo, glm::vec3(0.95f))));
            CHECK(closed_and_oriented(m));
            double volume = 0;
            std::size_t facing = 0, zero_area = 0;
            for (std::size_t i = 0; i < m.triangle_count(); ++i) {
                const glm::uvec3 t = m.triangles[i];
                volume += glm::dot(glm::dvec3(m.positions[t.x]),
                                   glm::cross(glm::dvec3(m.positions[t.y]), glm::dvec3(m.positions[t.z])));
                const glm::vec3 g = geometric_normal(m, i);
                zero_area += !(glm::length(g) > 0.0f);
                // Smooth: the shading normals agree with the faces they belong to.
                facing += glm::dot(glm::normalize(g), m.normals[t.x]) > 0.5f;
            }
            CHECK(zero_area == 0);
            CHECK(volume > 0.0);  // outward
            CHECK(facing > m.triangle_count() * 99 / 100);
            const auto [lo, hi] = mesh_bounds(m);
            const glm::vec3 e = hi - lo;
            CHECK(std::max({e.x, e.y, e.z}) >= 36.0f);
            CHECK(std::max({e.x, e.y, e.z}) <= 44.0f);

            const LoadedMesh b = detail::generate_mesh_object(family, seed);  // same seed, same bytes
            CHECK(std::memcmp(m.positions.data(), b.mesh.positions.data(), m.positions.size() * 12) == 0);
            CHECK(std::memcmp(m.normals.data(), b.mesh.normals.data(), m.normals.size() * 12) == 0);
            CHECK(m.triangles == b.mesh.triangles);
            const LoadedMesh c = detail::generate_mesh_object(family, seed + 10);
            CHECK((c.mesh.positions.size() != m.positions.size() ||
                   std::memcmp(m.positions.data(), c.mesh.positions.data(), m.positions.size() * 12) != 0));
        }
    }
    CHECK_THROWS_AS(detail::generate_mesh_object("teapot", 1), InputError);
}

TEST_CASE("mesh scenes: specs, the grid around the mesh, the floor, mesh files", "[mesh]") {
    CHECK(scene_spec_name("knot") == "knot:seed=0");
    CHECK(scene_spec_name("blob:floor=1,seed=4") == "blob:seed=4,floor=1");
    CHECK(scene_spec_name("blob:floor=0,seed=4") == "blob:seed=4");
    CHECK(scene_spec_name("x/bunny.OBJ") == "x/bunny.OBJ");
    CHECK_THROWS_WITH(make_scene("knot:colour=3"), Contains("unknown option 'colour'") && Contains("floor=0|1"));
    CHECK_THROWS_WITH(make_scene("knot:floor=2"), Contains("floor must be 0 or 1"));
    CHECK_THROWS_WITH(make_scene("room:floor=1"), Contains("unknown option 'floor'") && Contains("(expected seed=N)"));

    const VoxelScene s = make_scene("superquadric:seed=3");
    CHECK(s.name == "superquadric:seed=3");
    CHECK(s.solid_count() == 0);
    CHECK(s.camera.orbit);
    REQUIRE_NOTHROW(validate_mesh(s.mesh, s.palette.size(), s.name));
    const auto [lo, hi] = mesh_bounds(s.mesh);
    CHECK(glm::all(glm::greaterThanEqual(lo, glm::vec3(1.9f))));  // the margin
    CHECK(glm::all(glm::lessThanEqual(hi, glm::vec3(s.size) - 1.9f)));
    CHECK(generate_scene("superquadric", 3).mesh.positions == s.mesh.positions);

    const VoxelScene f = make_scene("superquadric:seed=3,floor=1");
    CHECK(f.name == "superquadric:seed=3,floor=1");
    CHECK(f.solid_count() == std::size_t(f.size.x) * std::size_t(f.size.z));  // one layer
    for (int z = 0; z < f.size.z; z += 7)
        for (int x = 0; x < f.size.x; x += 7) CHECK(f.solid({x, 0, z}));
    const auto [flo, fhi] = mesh_bounds(f.mesh);
    CHECK(flo.y == Approx(1.0f).margin(1e-4));  // standing on the floor's top face
    CHECK(flo.x >= 9.9f);                        // the floor reaches 10 m beyond the object
    REQUIRE_NOTHROW(validate_mesh(f.mesh, f.palette.size(), f.name));
    CHECK(f.palette.size() == s.palette.size() + 1);

    // A mesh file: placed in a grid of air around it, in its own units, named by its path.
    test::TempDir dir("mesh-scene");
    spit(dir / "cube.obj", kCubeObj);
    spit(dir / "cube.mtl", kCubeMtl);
    const VoxelScene c = make_scene(dir / "cube.obj");
    CHECK(c.name == dir / "cube.obj");
    CHECK(c.size == glm::ivec3(5));
    CHECK(c.mesh.triangle_count() == 12);
    CHECK(mesh_bounds(c.mesh).first == glm::vec3(2.0f));
    CHECK(c.camera.orbit);
    // Millimetres read as metres would need a grid beyond the limits: refused with a hint.
    spit(dir / "mm.obj", "v 0 0 0\nv 9000 0 0\nv 0 9000 0\nf 1 2 3\n");
    CHECK_THROWS_WITH(make_scene(dir / "mm.obj"), Contains("mm.obj") && Contains("millimetres"));
}

TEST_CASE("the camera orbits a mesh scene: its blocks stand for the mesh in the path code", "[mesh]") {
    const VoxelScene s = make_scene("blob:seed=5");
    const VoxelScene g = detail::with_mesh_blocks(s);
    CHECK(g.mesh.empty());
    const auto [lo, hi] = mesh_bounds(s.mesh);
    const glm::ivec3 centre((lo + hi) * 0.5f);
    CHECK(g.solid(centre));                    // inside the object: filled
    CHECK_FALSE(g.solid({0, 0, 0}));           // the margin: air
    CHECK(g.solid_count() > 1000);
    std::size_t outside = 0;  // every vertex lies in a solid block
    for (const glm::vec3& v : s.mesh.positions) outside += !g.solid(glm::ivec3(glm::floor(v)));
    CHECK(outside == 0);

    const CameraPath p = make_camera_path(s, CameraPathKind::Auto, 31, 1);  // auto = orbit (camera.orbit)
    REQUIRE(p.keys.size() >= 2);
    for (const CameraKey& k : p.keys) {
        CHECK(clear_of_blocks_in_open_air(s, k.position, 0.5f));
        CHECK(clear_of_blocks_in_open_air(g, k.position, 0.5f));
        const CameraPose pose{k.position, glm::normalize(k.orientation * glm::vec3(0, 0, -1)), glm::vec3(0, 1, 0)};
        CHECK(front_geometry_share(s, pose, 8) > 0.0f);  // looking at the object
    }
}

TEST_CASE("mesh: every file of the fuzz corpus loads or is refused cleanly", "[mesh]") {
    // fuzz/corpus/mesh/: the seeds of fuzz_mesh (first byte: 0 OBJ, 1 PLY, 2 glTF, 3 GLB) and the inputs it found
    // over its campaigns (e.g. a PLY face of no index, which once aborted the library that read PLY then).
    static const char* names[4] = {"seed.obj", "seed.ply", "seed.gltf", "seed.glb"};
    int files = 0, loaded = 0;
    for (const auto& e : std::filesystem::directory_iterator(std::string(NGI_SOURCE_DIR) + "/fuzz/corpus/mesh")) {
        const std::string b = test::slurp(e.path().string());
        if (b.empty()) continue;
        INFO(e.path().filename().string());
        ++files;
        try {
            const LoadedMesh l = parse_mesh(b.substr(1), names[std::uint8_t(b[0]) % 4]);
            CHECK_NOTHROW(validate_mesh(l.mesh, l.materials.size() + 1, "corpus"));
            ++loaded;
        } catch (const InputError&) {
        }
    }
    CHECK(files >= 10);
    CHECK(loaded >= 10);  // the seeds are valid files
}

TEST_CASE("mesh: an OBJ line element of one vertex is no triangle: refused when the file has none", "[mesh]") {
    // fuzz_mesh's 807,213th input of the round-two campaign (fuzz/corpus/mesh/line_of_one_vertex_after_usemtl.obj)
    // leaked inside the library that read OBJ then. ngi's reader (mesh_obj.cpp) counts a line of k vertices as k - 1
    // segments, so a line of one is nothing: the file is refused because it has no triangle, and loads with one.
    using namespace ngi;
    CHECK_THROWS_WITH(parse_mesh("v 0 1 0\nv 0 1 1\nusemtl 4\nl 2 1\nusemtl 1\nl 2\n", "bad.obj"),
                      Catch::Contains("no triangle with an area (0 degenerate, 1 points or lines)"));
    const LoadedMesh l = parse_mesh("v 0 1 0\nv 0 1 1\nv 1 1 0\nusemtl 4\nl 2 1\nusemtl 1\nl 2\nf 1 2 3\n", "ok.obj");
    CHECK(l.mesh.triangle_count() == 1);
    CHECK(l.dropped_primitives == 1);
}

TEST_CASE("mesh: OBJ index tokens: more than three parts refused, every index checked, leading zeros read", "[mesh]") {
    // "l 1/1/1/1 2" once made the library that read OBJ then write past its vertex array (valgrind, behind
    // fuzz_mesh's unexplained ASan report; fuzz/corpus/mesh/line_index_with_four_parts.obj). The input class now:
    // an index of more than three parts is refused, naming the line and the token.
    using namespace ngi;
    const std::string head = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n";
    CHECK_THROWS_WITH(parse_mesh(head + "l 1/1/1/1 2\nl 1/1/1/1 3\nl 1 2 3\n", "bad.obj"),
                      Catch::Contains("OBJ line 6") && Catch::Contains("'1/1/1/1' has more than three parts"));
    CHECK_THROWS_WITH(parse_mesh(head + "f 1 2 3/1/1/1\n", "bad.obj"), Catch::Contains("'3/1/1/1' has more than three"));
    // A second part is a texture coordinate index, whatever else the file has: none here, so it is out of range.
    CHECK_THROWS_WITH(parse_mesh("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1/1/1 2 3\n", "bad.obj"),
                      Catch::Contains("OBJ line 5: texture coordinate index 1 is out of range (the file has 0)"));
    // v//vn, v/vt/vn and a trailing slash load.
    CHECK_NOTHROW(parse_mesh("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n", "ok.obj"));
    CHECK_NOTHROW(parse_mesh(head + "f 1/1/1 2/1/1 3/1/1\nl 1/1/1/ 2\n", "ok.obj"));
    // Leading zeros are read as numbers (refused before only because that library misread them): "010" is vertex
    // 10, out of range here; "-01" is -1, the last vertex so far.
    CHECK_THROWS_WITH(parse_mesh(head + "f 010 2 3\n", "bad.obj"), Catch::Contains("vertex index 10 is out of range"));
    CHECK(parse_mesh(head + "f 1 2 -01\n", "ok.obj").mesh.triangle_count() == 1);
}

TEST_CASE("mesh: a PLY with a second vertex or face element is refused", "[mesh]") {
    // Such a file once made the library that read PLY then write past its vertex array (valgrind; through parse_mesh
    // glibc aborted with "malloc(): corrupted top size"; fuzz/corpus/mesh/ply_second_vertex_element.ply). ngi's
    // reader (mesh_ply.cpp) reads one vertex and one face element and refuses a second, naming the header line.
    using namespace ngi;
    const std::string props = "property float x\nproperty float y\nproperty float z\n";
    const std::string face = "element face 1\nproperty list uchar int vertex_indices\n";
    CHECK_THROWS_WITH(parse_mesh("ply\nformat ascii 1.0\nelement vertex 1\n" + props + "element vertex 3\n" + props +
                                     face + "end_header\n0 0 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                                 "bad.ply"),
                      Catch::Contains("a second 'vertex' element on header line 7"));
    CHECK_THROWS_WITH(parse_mesh("ply\nformat ascii 1.0\nelement vertex 3\n" + props + face + face +
                                     "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n",
                                 "bad.ply"),
                      Catch::Contains("a second 'face' element"));
}

TEST_CASE("mesh: a texture statement before any newmtl applies to nothing and is skipped", "[mesh]") {
    // fuzz_mesh's 811,578th input of the round-two campaign (fuzz/corpus/mesh/texture_before_newmtl_in_self_mtllib.obj):
    // an OBJ naming itself as its mtllib, with a bare "map_ns" line, crashed the library that read OBJ then (it wrote
    // the texture into a material that did not exist). ngi's reader reads no texture and skips every statement
    // before the first newmtl: that input is now refused only because it has no triangle.
    CHECK_THROWS_WITH(parse_mesh("map_ns\nmtllib fuzz.obj", "fuzz.obj"), Contains("fuzz.obj") && Contains("no triangles"));
    test::TempDir dir("mesh-mtl");
    const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
    // A library whose texture lines come first: loads when it then defines the material the OBJ uses (a material
    // without Kd keeps the 0.6 sRGB grey such files always got), and is refused, naming the usemtl, when it does not.
    for (const std::string mtl : {"map_Kd x.png\nnewmtl a\n", "# c\n  bump x.png\nnewmtl a\n", "norm x.png\r\nnewmtl a\n"}) {
        INFO(mtl);
        spit(dir / "t.mtl", mtl);
        spit(dir / "t.obj", "mtllib t.mtl\n" + tri);
        const LoadedMesh l = load_mesh(dir / "t.obj");
        REQUIRE(l.materials.size() == 1);
        CHECK(l.materials[0].albedo.x == Approx(srgb(0.6f)));
    }
    for (const std::string mtl : {"disp x.png\n", "map_Kd -bm 2 x.png\n"}) {
        spit(dir / "t.mtl", mtl);
        CHECK_THAT(mesh_error(dir / "t.obj"), Contains("usemtl 'a' names no material") && Contains("t.mtl defines none"));
    }
    // A form feed is no line break: refused as a control character, naming the library and its line.
    spit(dir / "t.mtl", "Kd 1 1 1\fmap_Kd -type sphere x\n");
    CHECK_THAT(mesh_error(dir / "t.obj"), Contains("material library t.mtl line 1: control character 12"));
    // After a newmtl the same statements are a material's textures: the mesh loads with the library's colour.
    spit(dir / "t.mtl", "# c\nnewmtl a\nKd 0.5 0.5 0.5\nmap_Kd -bm 2 x.png\nbump x.png\nnorm y.png\nmap_ns z.png\n");
    const LoadedMesh l = load_mesh(dir / "t.obj");
    CHECK(l.mesh.triangle_count() == 1);
    REQUIRE(l.materials.size() == 1);
    CHECK_THAT(l.materials[0].albedo.x, Catch::Matchers::WithinAbs(0.214, 0.01));  // sRGB 0.5 -> linear 0.214
    // Colours and scalars before a newmtl are skipped too: the file loads.
    spit(dir / "t.mtl", "Kd 1 1 1\nNs 3\nd 0.5\nillum 2\nnewmtl a\nKd 0.5 0.5 0.5\n");
    CHECK_NOTHROW(load_mesh(dir / "t.obj"));
}

TEST_CASE("mesh readers: what each refuses that a lenient reader would misread, naming the line or element", "[mesh]") {
    // One parser per format (mesh_obj.cpp, mesh_ply.cpp, mesh_gltf.cpp with tinygltf): each input below would load
    // as a different mesh than the file states through a lenient reader (tinyobjloader 2.0.0rc10 reads "x" and "nan"
    // as 0 and 4294967295 as -1, a relative index), so it is refused.
    const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    CHECK_THROWS_WITH(parse_mesh("v 1 x 3\n" + tri + "f 1 2 3\n", "a.obj"), Contains("a.obj: OBJ line 1: 'x' is not a number"));
    CHECK_THROWS_WITH(parse_mesh("v 0 nan 0\n" + tri + "f 2 3 4\n", "a.obj"), Contains("OBJ line 1: position is not finite"));
    CHECK_THROWS_WITH(parse_mesh(tri + "f 4294967295 1 2\n", "a.obj"), Contains("vertex index 4294967295 is out of range"));
    CHECK_THROWS_WITH(parse_mesh(tri + "v 0 0 0 1 0\nf 1 2 3\n", "a.obj"), Contains("OBJ line 4: 5 numbers for a v"));
    CHECK_THROWS_WITH(parse_mesh("v 0 0 0 1 0 0\n" + tri.substr(8) + "f 1 2 3\n", "a.obj"),
                      Contains("1 of its 3 vertices have a colour (x y z r g b): all or none"));
    CHECK_THROWS_WITH(parse_mesh("v 0 0 0 0\n" + tri + "f 2 3 4\n", "a.obj"), Contains("OBJ line 1: w is 0"));
    CHECK_THROWS_WITH(parse_mesh("v 0 0 0\rv 1 0 0\n" + tri + "f 3 4 5\n", "a.obj"), Contains("OBJ line 1: control character 13"));
    CHECK_THROWS_WITH(parse_mesh(tri + "f 1 2 \\\n3\n", "a.obj"), Contains("OBJ line 4: a line continued with a backslash"));
    CHECK(parse_mesh("v 0 0 0 1\nv 2 0 0 2\nv 0 3 0 3\nf 1 2 3\n", "w.obj").mesh.positions[1] == glm::vec3(1, 0, 0));

    const std::string head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                             "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    CHECK_THROWS_WITH(parse_mesh(head + "0 0 0 7\n1 0 0\n0 1 0\n3 0 1 2\n", "a.ply"),
                      Contains("PLY vertex 0: 4 values on its line, its properties take 3"));
    CHECK_THROWS_WITH(parse_mesh(head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n", "a.ply"),
                      Contains("PLY face 0: vertex index -1 is out of range (3 vertices)"));
    CHECK_THROWS_WITH(parse_mesh(head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2.5\n", "a.ply"), Contains("PLY face 0: '2.5' is not a int"));

    auto [j, bin] = gltf_quad(true);
    nlohmann::json q = j;
    q["accessors"][0]["componentType"] = 5123;  // KHR_mesh_quantization's unsigned short positions
    CHECK_THROWS_WITH(parse_mesh(glb_file(q, bin), "q.glb"), Contains("q.glb: glTF mesh 0 primitive 0 POSITION (accessor 0) "
                                                                     "is not of a type read here (componentType 5123"));
    q = j;
    q["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"] = {{"bufferView", 0}};
    CHECK_THROWS_WITH(parse_mesh(glb_file(q, bin), "d.glb"), Contains("Draco-compressed"));
    // A GLB whose bytes after the JSON chunk are 4, too few for a chunk header: refused before tinygltf sees it.
    std::string glb = glb_file(j, bin);
    std::uint32_t json_len = 0;
    std::memcpy(&json_len, glb.data() + 12, 4);
    glb.resize(20 + json_len + 4);
    const std::uint32_t length = std::uint32_t(glb.size());
    std::memcpy(glb.data() + 8, &length, 4);
    CHECK_THROWS_WITH(parse_mesh(glb, "j.glb"), Contains("j.glb: GLB: bytes after the JSON chunk are no chunk"));
    q = j;
    q.erase("scene");
    q.erase("scenes");
    CHECK_THROWS_WITH(parse_mesh(glb_file(q, bin), "s.glb"), Contains("glTF has no scene"));
}

TEST_CASE("mesh readers: hostile sizes stay bounded (indices, shared accessors, repeated roots, huge polygons)", "[mesh][limits]") {
    const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    // A relative index of the most negative int64 (its negation would overflow): refused, naming it.
    CHECK_THROWS_WITH(parse_mesh(tri + "f 1 2 -9223372036854775808\n", "a.obj"),
                      Contains("relative vertex index -9223372036854775808 reaches before the first of the 3"));
    // PLY indices of a float type are no indices.
    CHECK_THROWS_WITH(parse_mesh("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                 "property float z\nelement face 1\nproperty list uchar float vertex_indices\nend_header\n"
                                 "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "a.ply"),
                      Contains("PLY face list 'vertex_indices' holds floats"));
    // 250 primitives naming one accessor of 80,000 vertices without a buffer view (zeros, allowed up to 16 x the
    // file): refused before any is read, not read 250 times.
    auto [j, bin] = gltf_quad(true);
    j["accessors"].push_back({{"componentType", 5126}, {"count", 80000}, {"type", "VEC3"}});
    for (int k = 0; k < 250; ++k) j["meshes"][0]["primitives"].push_back({{"attributes", {{"POSITION", 4}}}});
    CHECK_THROWS_WITH(parse_mesh(glb_file(j, bin), "shared.glb"),
                      Contains("shared.glb: glTF primitives hold 20000004 vertices") && Contains("more than the limits"));
    // A scene listing its root 2^20 + 1 times (a 2 MB file): the walk stops at 2^20 placements.
    std::tie(j, bin) = gltf_quad(true);
    j["scenes"][0]["nodes"] = std::vector<int>((1 << 20) + 1, 1);
    CHECK_THROWS_WITH(parse_mesh(glb_file(j, bin), "roots.glb"), Contains("places more than 1048576 nodes"));
    // A polygon of 20,000 corners on a comb (every other corner a notch): ear clipping within its budget, then fanned.
    std::string comb, face = "f";
    for (int i = 0; i < 10000; ++i) {
        comb += "v " + std::to_string(i) + " 0 0\nv " + std::to_string(i) + ".5 " + (i % 2 ? "1" : "3") + " 0\n";
        face += " " + std::to_string(2 * i + 1) + " " + std::to_string(2 * i + 2);
    }
    const auto t0 = std::chrono::steady_clock::now();
    const LoadedMesh l = parse_mesh(comb + face + "\n", "comb.obj");
    CHECK(l.mesh.triangle_count() + l.dropped_degenerate == 19998);
    CHECK(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < 10.0);
}

TEST_CASE("mesh readers: the inputs of fuzz_mesh's corpus that load otherwise than with the old loader", "[mesh]") {
    // Issue 49 ran the old loader and the new readers over the 2,127 inputs of the first campaign's corpus: these are
    // the classes that load differently, each on purpose (the rest load bit for bit the same, or as before refused).
    // A `g` or `o` naming the group already current continues its part: its faces share vertices (3, not 9).
    const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    CHECK(parse_mesh(tri + "g a\nf 1 2 3\ng a\nf 1 3 2\ng a\nf 2 1 3\n", "g.obj").mesh.positions.size() == 3);
    CHECK(parse_mesh(tri + "g a\nf 1 2 3\ng b\nf 1 3 2\n", "g.obj").mesh.positions.size() == 6);
    // A polygon that is not simple (a corner repeated: no ear) is fanned; the old loader dropped the triangles it had
    // not found yet.
    const LoadedMesh fan = parse_mesh("v 0 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\nv 1 3 0\nf 1 2 3 1 4 5\n", "fan.obj");
    CHECK(fan.mesh.triangle_count() + fan.dropped_degenerate == 4);
    // A statement after leading blanks is read (the old loader skipped " f 1 2 3").
    CHECK(parse_mesh(tri + "f 1 2 3\n f 1 3 2\n", "b.obj").mesh.triangle_count() == 2);
    // A face mixing corners with and without a normal: the others get computed ones (the old loader gave them the
    // file's first vn, here -z).
    const LoadedMesh mixed = parse_mesh(tri + "vn 0 0 -1\nvn 0 0 1\nf 1//2 2 3\n", "n.obj");
    for (const glm::vec3& n : mixed.mesh.normals) CHECK(n == glm::vec3(0, 0, 1));
    // glTF COLOR_0 of unsigned bytes without the `normalized` flag the specification requires: normalized anyway.
    auto [j, bin] = gltf_quad(true);
    std::string b = bin;
    std::string colours;
    for (int i = 0; i < 4; ++i) colours += std::string("\xff\x80\x00\xff", 4);
    j["buffers"][0]["byteLength"] = b.size() + 16;
    j["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", b.size()}, {"byteLength", 16}});
    j["accessors"].push_back({{"bufferView", 4}, {"componentType", 5121}, {"count", 4}, {"type", "VEC4"}});
    j["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = 4;
    const LoadedMesh c = parse_mesh(glb_file(j, b + colours), "c.glb");
    REQUIRE(c.materials.size() == 1);
    CHECK(c.materials[0].albedo.x == Approx(0.5f));                  // base 0.5 x 1
    CHECK(c.materials[0].albedo.y == Approx(0.3f * 128.0f / 255.0f));  // base 0.3 x 128/255
    // A node's scale, rotation, translation or matrix of the wrong size is refused (the old loader ignored it), as
    // are positions that are not three floats (it read their bytes as floats) and colours of signed bytes (it
    // dropped them).
    j["nodes"][0]["scale"] = {2, 2};
    CHECK_THROWS_WITH(parse_mesh(glb_file(j, b + colours), "s.glb"), Contains("glTF node 0 scale is not 3 numbers"));
}
