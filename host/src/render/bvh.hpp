// A bounding-volume hierarchy over a TriangleMesh, built on the host (binned SAH) and flattened into the compact
// layout kernels/bvh.cl traverses. Library-internal (the renderer, the BVH tests and perf/bench_bvh use it).
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "ngi/mesh.hpp"

namespace ngi::detail {

// The traversal stack of kernels/bvh.cl (passed as -D BVH_STACK by bvh_defines(): defined only here); the builder
// keeps the tree's depth below it.
constexpr int kBvhStackSize = 64;
// Builder knobs (host only).
constexpr int kBvhMaxLeaf = 4;      // triangles per leaf at most
constexpr int kBvhBins = 16;        // SAH bins per axis and split

// The flattened tree. Node i is two float4s (nodes[2i], nodes[2i+1]):
//   [lo.x, lo.y, lo.z, bits(a)] [hi.x, hi.y, hi.z, bits(b)]   (bits = the int32's bit pattern)
//   leaf     (b >= 1):  triangles a .. a + b - 1 (in BVH order)
//   interior (b <= 0):  split axis -b; left child i + 1 (depth-first order), right child a
// Triangles in BVH order: three float4s each (vertex 0, 1, 2; w unused) in `tri_vertices`, and the int4
// (vertex index 0, 1, 2, palette index) in `tri_info`; the original triangle of BVH slot k is `order[k]`.
// Per-vertex shading normals in `vertex_normals` (float4, w unused).
struct Bvh {
    std::vector<float> nodes;           // 8 floats per node
    std::vector<float> tri_vertices;    // 12 floats per triangle
    std::vector<std::int32_t> tri_info; // 4 ints per triangle
    std::vector<float> vertex_normals;  // 4 floats per vertex
    std::vector<std::uint32_t> order;   // BVH slot -> triangle index in the mesh
    int depth = 0;                      // levels of the tree (1 = a single leaf)

    std::size_t node_count() const { return nodes.size() / 8; }
    std::size_t triangle_count() const { return order.size(); }
};

// Builds the tree over every triangle of `mesh` (validated by the caller: validate_mesh). An empty mesh gives an
// empty Bvh (no nodes). Deterministic: the same mesh gives the same bytes.
Bvh build_bvh(const TriangleMesh& mesh);

// The -D options kernels/bvh.cl needs (the constants above).
std::string bvh_defines();

// A ray's closest hit, as the device reports it (for tests and benchmarks).
struct RayHit {
    float t = 0;          // distance along the ray (in units of |d|); only meaningful when prim >= 0
    std::int32_t prim = -1;  // triangle index in the mesh, -1 = no hit within [0, tmax]
    float u = 0, v = 0;   // barycentric weights of vertices 1 and 2
};

// Watertight ray/triangle intersection (Woop, Benthin and Wald, JCGT 2013), the same arithmetic as bvh.cl, on the
// host: a hit with 0 < t <= tmax. For brute-force references.
bool intersect_triangle(glm::vec3 o, glm::vec3 d, glm::vec3 a, glm::vec3 b, glm::vec3 c, float tmax, float& t,
                        float& u, float& v);

// Closest hit by testing every triangle (the reference the BVH is checked against).
RayHit intersect_brute_force(const TriangleMesh& mesh, glm::vec3 o, glm::vec3 d, float tmax);

}  // namespace ngi::detail

namespace ngi {
class Device;
}

namespace ngi::detail {

class Context;
class Buffer;

// A Bvh uploaded to a device: its nodes, triangles, triangle info and vertex normals (one-element placeholders
// for an empty mesh: OpenCL refuses zero-sized buffers). The renderer binds them to the path tracer's kernels;
// trace() queries batches of rays through kernels/bvh.cl's bvh_trace_rays (the BVH tests and perf/bench_bvh).
class DeviceBvh {
public:
    DeviceBvh(const Device& device, const Bvh& bvh);
    ~DeviceBvh();
    DeviceBvh(DeviceBvh&&) noexcept;
    DeviceBvh& operator=(DeviceBvh&&) noexcept;

    // rays: 8 floats per ray (origin x, y, z, tmax, direction x, y, z, unused). Closest hits (any hits: the first
    // found, for shadow rays) with prim as the mesh's triangle index. steps (if given): node visits + triangle
    // tests per ray. device_ms (if given): the wall time of the launch and clFinish around the kernel (no transfers).
    std::vector<RayHit> trace(const std::vector<float>& rays, bool any, std::vector<std::uint32_t>* steps = nullptr,
                              double* device_ms = nullptr);

    const Buffer& nodes() const;
    const Buffer& triangles() const;
    const Buffer& triangle_info() const;
    const Buffer& vertex_normals() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ngi::detail
