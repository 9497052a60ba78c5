// Binned-SAH BVH builder (Wald 2007, "On fast construction of SAH-based bounding volume hierarchies"), flattened
// depth-first for kernels/bvh.cl, and the host reference of its ray/triangle test.
#include "render/bvh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "ngi/host_memory.hpp"

namespace ngi::detail {
namespace {

struct Box {
    glm::vec3 lo{std::numeric_limits<float>::infinity()}, hi{-std::numeric_limits<float>::infinity()};
    void grow(glm::vec3 p) { lo = glm::min(lo, p); hi = glm::max(hi, p); }
    void grow(const Box& b) { lo = glm::min(lo, b.lo); hi = glm::max(hi, b.hi); }
    bool empty() const { return lo.x > hi.x; }
    float area() const {
        if (empty()) return 0.0f;
        const glm::vec3 e = hi - lo;
        return 2.0f * (e.x * e.y + e.y * e.z + e.z * e.x);
    }
};

// The bin of a centroid coordinate: clamped in float before the conversion, so that a denormal extent (scale
// infinite, 0 * inf = NaN) or rounding past the last bin never reaches an undefined float -> int conversion.
int bin_of(float c, float lo, float scale) {
    const float f = (c - lo) * scale;
    return f >= float(kBvhBins - 1) ? kBvhBins - 1 : (f > 0.0f ? int(f) : 0);
}

struct BvhBuilder {
    std::vector<Box> tri_box;
    std::vector<glm::vec3> centroid;
    std::vector<std::uint32_t> idx;  // triangle indices, partitioned in place
    struct Node {
        Box box;
        std::int32_t a = 0, b = 0;
    };
    std::vector<Node> nodes;
    int depth = 0;

    // Node over idx[first, first + count) at depth `level` (1 = root); returns its index.
    std::int32_t build(std::uint32_t first, std::uint32_t count, int level) {
        depth = std::max(depth, level);
        const auto me = std::int32_t(nodes.size());
        nodes.emplace_back();
        Box box, cbox;
        for (std::uint32_t i = first; i < first + count; ++i) {
            box.grow(tri_box[idx[i]]);
            cbox.grow(centroid[idx[i]]);
        }
        nodes[std::size_t(me)].box = box;
        auto make_leaf = [&] {
            nodes[std::size_t(me)].a = std::int32_t(first);
            nodes[std::size_t(me)].b = std::int32_t(count);
            return me;
        };
        if (count <= std::uint32_t(kBvhMaxLeaf)) return make_leaf();

        // Best split over kBvhBins centroid bins on each axis: cost = A_left N_left + A_right N_right. Nodes over
        // kBvhMaxLeaf triangles always split (a fixed leaf bound keeps the kernel's leaf loop short).
        int best_axis = -1, best_bin = 0;
        float best_cost = std::numeric_limits<float>::infinity();
        const glm::vec3 extent = cbox.hi - cbox.lo;
        for (int axis = 0; axis < 3; ++axis) {
            if (!(extent[axis] > 0.0f)) continue;
            std::array<Box, kBvhBins> bins;
            std::array<std::uint32_t, kBvhBins> n{};
            const float scale = float(kBvhBins) / extent[axis];
            for (std::uint32_t i = first; i < first + count; ++i) {
                const std::uint32_t t = idx[i];
                const int k = bin_of(centroid[t][axis], cbox.lo[axis], scale);
                bins[std::size_t(k)].grow(tri_box[t]);
                ++n[std::size_t(k)];
            }
            std::array<float, kBvhBins> right_cost{};
            Box acc;
            std::uint32_t cnt = 0;
            for (int k = kBvhBins - 1; k > 0; --k) {
                acc.grow(bins[std::size_t(k)]);
                cnt += n[std::size_t(k)];
                right_cost[std::size_t(k)] = acc.area() * float(cnt);
            }
            acc = Box{};
            cnt = 0;
            for (int k = 0; k < kBvhBins - 1; ++k) {
                acc.grow(bins[std::size_t(k)]);
                cnt += n[std::size_t(k)];
                const float c = acc.area() * float(cnt) + right_cost[std::size_t(k) + 1];
                if (cnt > 0 && cnt < count && c < best_cost) {
                    best_cost = c;
                    best_axis = axis;
                    best_bin = k;
                }
            }
        }
        // The stack bound: near the depth limit, split at the median (depth then grows by one per halving).
        const bool near_limit = level >= kBvhStackSize - 32;
        std::uint32_t mid;
        int axis = best_axis;
        if (!near_limit && best_axis >= 0) {
            const float scale = float(kBvhBins) / extent[axis];
            const auto it = std::partition(idx.begin() + first, idx.begin() + first + count, [&](std::uint32_t t) {
                return bin_of(centroid[t][axis], cbox.lo[axis], scale) <= best_bin;
            });
            mid = std::uint32_t(it - idx.begin());
        } else {
            // No centroid extent (every centroid equal) or near the depth limit: the object median on the widest
            // axis, ties broken by triangle index so the order is deterministic.
            axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
            mid = first + count / 2;
            std::nth_element(idx.begin() + first, idx.begin() + mid, idx.begin() + first + count,
                             [&](std::uint32_t l, std::uint32_t r) {
                                 return centroid[l][axis] < centroid[r][axis] ||
                                        (centroid[l][axis] == centroid[r][axis] && l < r);
                             });
        }
        build(first, mid - first, level + 1);  // the left child is me + 1
        const std::int32_t right = build(mid, first + count - mid, level + 1);
        nodes[std::size_t(me)].a = right;
        nodes[std::size_t(me)].b = -axis;
        return me;
    }
};

float bits_as_float(std::int32_t i) {
    float f;
    std::memcpy(&f, &i, sizeof f);
    return f;
}

}  // namespace

Bvh build_bvh(const TriangleMesh& mesh) {
    Bvh out;
    const std::size_t ntri = mesh.triangles.size();
    if (ntri == 0) return out;
    // What the build and its result hold at once, checked before any of it is allocated: per triangle the
    // builder's box, centroid and index, the result's order, vertices (3 x float4) and info (int4), and their device
    // copies (host memory on a CPU device); the nodes (builder and flat, ~2 per kBvhMaxLeaf triangles); per vertex
    // its normal (float4) and device copy. A mesh under the mesh limits fits the default budget; a smaller
    // NGI_HOST_MEMORY_LIMIT is kept (issue 51: a 400 KB .glb of 16.8 M instanced triangles reached 3.7 GB at 1G).
    const std::uint64_t nodes = 2 * std::uint64_t(ntri) / std::uint64_t(kBvhMaxLeaf) + 1;
    const std::uint64_t per_triangle = sizeof(Box) + sizeof(glm::vec3) + 4 + 4 + 2 * (12 + 4) * sizeof(float);
    const std::uint64_t per_node = sizeof(BvhBuilder::Node) + 2 * 8 * sizeof(float);
    check_host_memory("build the BVH of " + std::to_string(ntri) + " triangles",
                      ntri * per_triangle + nodes * per_node + mesh.positions.size() * 2 * 4 * sizeof(float));
    BvhBuilder b;
    b.tri_box.resize(ntri);
    b.centroid.resize(ntri);
    b.idx.resize(ntri);
    for (std::size_t t = 0; t < ntri; ++t) {
        const glm::uvec3 v = mesh.triangles[t];
        Box box;
        for (int k = 0; k < 3; ++k) box.grow(mesh.positions[v[k]]);
        b.tri_box[t] = box;
        b.centroid[t] = 0.5f * (box.lo + box.hi);
        b.idx[t] = std::uint32_t(t);
    }
    b.nodes.reserve(2 * ntri / std::size_t(kBvhMaxLeaf) + 1);
    b.build(0, std::uint32_t(ntri), 1);
    out.depth = b.depth;

    out.nodes.resize(b.nodes.size() * 8);
    for (std::size_t i = 0; i < b.nodes.size(); ++i) {
        const auto& n = b.nodes[i];
        float* q = &out.nodes[8 * i];
        q[0] = n.box.lo.x; q[1] = n.box.lo.y; q[2] = n.box.lo.z; q[3] = bits_as_float(n.a);
        q[4] = n.box.hi.x; q[5] = n.box.hi.y; q[6] = n.box.hi.z; q[7] = bits_as_float(n.b);
    }
    out.order = b.idx;
    out.tri_vertices.resize(ntri * 12, 0.0f);
    out.tri_info.resize(ntri * 4);
    for (std::size_t k = 0; k < ntri; ++k) {
        const std::uint32_t t = b.idx[k];
        const glm::uvec3 v = mesh.triangles[t];
        for (int j = 0; j < 3; ++j) {
            const glm::vec3 p = mesh.positions[v[j]];
            float* q = &out.tri_vertices[12 * k + 4 * std::size_t(j)];
            q[0] = p.x; q[1] = p.y; q[2] = p.z;
            out.tri_info[4 * k + std::size_t(j)] = std::int32_t(v[j]);
        }
        out.tri_info[4 * k + 3] = t < mesh.materials.size() ? mesh.materials[t] : 1;
    }
    out.vertex_normals.resize(mesh.positions.size() * 4, 0.0f);
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
        const glm::vec3 n = i < mesh.normals.size() ? mesh.normals[i] : glm::vec3(0, 1, 0);
        out.vertex_normals[4 * i] = n.x;
        out.vertex_normals[4 * i + 1] = n.y;
        out.vertex_normals[4 * i + 2] = n.z;
    }
    return out;
}

std::string bvh_defines() {
    return "-DBVH_STACK=" + std::to_string(kBvhStackSize);
}

bool intersect_triangle(glm::vec3 o, glm::vec3 d, glm::vec3 a, glm::vec3 b, glm::vec3 c, float tmax, float& t,
                        float& u, float& v) {
    // The axis where |d| is largest becomes z; x and y follow cyclically, swapped when d.z < 0 (keeps winding).
    const glm::vec3 ad = glm::abs(d);
    const int kz = ad.x >= ad.y && ad.x >= ad.z ? 0 : (ad.y >= ad.z ? 1 : 2);
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    if (d[kz] < 0.0f) std::swap(kx, ky);
    const float sx = d[kx] / d[kz], sy = d[ky] / d[kz], sz = 1.0f / d[kz];
    const glm::vec3 A = a - o, B = b - o, C = c - o;
    const float ax = A[kx] - sx * A[kz], ay = A[ky] - sy * A[kz];
    const float bx = B[kx] - sx * B[kz], by = B[ky] - sy * B[kz];
    const float cx = C[kx] - sx * C[kz], cy = C[ky] - sy * C[kz];
    const float U = cx * by - cy * bx, V = ax * cy - ay * cx, W = bx * ay - by * ax;
    if ((U < 0.0f || V < 0.0f || W < 0.0f) && (U > 0.0f || V > 0.0f || W > 0.0f)) return false;
    const float det = U + V + W;
    if (det == 0.0f) return false;
    const float T = U * (sz * A[kz]) + V * (sz * B[kz]) + W * (sz * C[kz]);
    if (det > 0.0f ? (T <= 0.0f || T > tmax * det) : (T >= 0.0f || T < tmax * det)) return false;
    const float inv = 1.0f / det;
    t = T * inv;
    u = V * inv;
    v = W * inv;
    return true;
}

RayHit intersect_brute_force(const TriangleMesh& mesh, glm::vec3 o, glm::vec3 d, float tmax) {
    RayHit best;
    float limit = tmax;
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
        const glm::uvec3 v = mesh.triangles[i];
        float t, u, w;
        if (intersect_triangle(o, d, mesh.positions[v.x], mesh.positions[v.y], mesh.positions[v.z], limit, t, u, w) &&
            (best.prim < 0 || t < best.t)) {
            best = {t, std::int32_t(i), u, w};
            limit = t;
        }
    }
    return best;
}

}  // namespace ngi::detail
