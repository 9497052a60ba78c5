// bench_bvh: ngi's OpenCL triangle-BVH traversal (kernels/bvh.cl through detail::DeviceBvh) side by side with
// Intel Embree 3 on the same mesh and the same rays (issue 27's performance targets). Prints one JSON object on
// stdout (and to --out), one summary line per case on stderr.
//
//   bench_bvh [--devices pocl[,rusticl]] [--meshes knot:seed=1,bunny,tube:1000000] [--bunny PATH]
//             [--rays primary,bounce,shadow] [--size 512] [--repeats 9] [--threads 2] [--quality high|medium]
//             [--out FILE]
//
// Meshes: "knot:seed=1" (any scene spec: ngi::make_scene(spec).mesh; when the scene has no triangles or its
// family is unknown, the benchmark's own torus-knot tube of ~100k triangles stands in), "tube:N" (this file's
// (2, 3) torus-knot tube of ~N triangles), "bunny" (--bunny PATH, by default tools/fetch_bunny.sh's output
// $NGI_ASSET_DIR/bunny.obj, else $XDG_CACHE_HOME or ~/.cache + /ngi/assets/bunny.obj; skipped when absent), "file:PATH" (any mesh
// ngi::load_mesh reads).
// Rays (8 floats each, the layout DeviceBvh::trace takes), the same array for both tracers:
//   primary  a pinhole camera, size x size pixels, looking at the centre of the mesh's bounding box from outside
//            it, far enough that the box fits a 40 degree field of view; the view is then narrowed (zoom 1, 0.85,
//            0.7, 0.55, 0.4: the first at which half of a 64 x 64 probe hits, else the one hitting most) so that
//            thin meshes (a knot) still cover a good part of the frame; the holes and edges miss. Rays ordered in
//            4 x 4 pixel tiles
//   bounce   one cosine-distributed diffuse ray from each primary hit (ngi's hits), its origin on the triangle
//            (barycentric point) offset along the geometric normal turned toward the camera by 1e-5 of the mesh's
//            bounding diagonal: the incoherent case
//   shadow   any-hit rays from the same points toward a fixed directional light, for points facing it
// Embree: one RTCScene of one RTC_GEOMETRY_TYPE_TRIANGLE, RTC_SCENE_FLAG_NONE, build quality --quality (HIGH by
// default: Embree's best tree for static geometry, spatial splits), device "threads=T" for its build. Traversal:
// rtcIntersect1 / rtcOccluded1 per ray on 1 thread and on T std::threads (chunks of 1024 rays from a shared
// counter), and packets of the CPU's native width (rtcIntersect8/rtcOccluded8 on AVX2, 16 on AVX-512) on T threads.
// ngi: build_bvh (single-threaded binned SAH) on the host, DeviceBvh::trace on each device of --devices (the
// device as ngi::Device::open names it; rusticl needs RUSTICL_ENABLE=llvmpipe), local size 64 as DeviceBvh
// fixes it. Times: "device" = DeviceBvh::trace's device_ms (the launch + clFinish around the kernel), "call" =
// the whole trace() call (ray upload, kernel, hit read-back, the host loop that maps BVH slots to triangles).
// Each ray set is traced once untimed first (PoCL compiles the kernel for the local size at its first launch; the
// steps per ray are read there), then --repeats rounds, each running every tracer once in turn, so that machine
// noise hits them alike; medians and minima over the rounds.
// Reported per case: median and minimum ms, Mrays/s at both, ngi's mean steps per ray (node visits + triangle
// tests, DeviceBvh's steps output), and throughput ratios ngi / Embree (> 1: ngi faster; issue 27's target is
// 0.3 against rtcIntersect1 on T threads). Per mesh: build times (ngi: build_bvh, median of 3; Embree: the commit,
// median of 3 on T threads, once on 1), node counts, depth and bytes of both trees (Embree's from its own
// statistics: a separate, untimed build on a device with verbose=2, its stdout captured).
// Agreement (fairness check): ngi against Embree's single-ray results (closest hit: hit/miss disagreements, and on
// rays both hit, the relative difference of t; any hit: occluded/visible disagreements). Embree's triangle test is
// not watertight under RTC_SCENE_FLAG_NONE (ngi's is), so a few rays through shared edges and vertices may
// disagree: the first 200 disputed rays are settled against the host's brute-force watertight reference
// (intersect_brute_force), which says which tracer was right.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <iostream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

#include <embree3/rtcore.h>
#include <nlohmann/json.hpp>

#include "bench_args.hpp"
#include "ngi/device.hpp"
#include "ngi/mesh.hpp"
#include "ngi/scene.hpp"
#include "render/bvh.hpp"

using json = nlohmann::json;
using ngi::detail::RayHit;

namespace {

constexpr float kPi = 3.14159265358979f;
constexpr float kTmax = 1.0e30f;

double now_ms() {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

using ngi_perf::arg;
using ngi_perf::split;

std::string loadavg() {
    std::ifstream f("/proc/loadavg");
    std::string a, b, c;
    f >> a >> b >> c;
    return a + " " + b + " " + c;
}

// ---- meshes ----------------------------------------------------------------------------------------------------

// A (2, 3) torus-knot tube (a trefoil), U segments along the knot by V around the tube: 2 U V triangles, closed,
// about 40 m across. The tube frame is the torus's radial direction (perpendicular to the knot's tangent).
ngi::TriangleMesh torus_knot_tube(std::size_t target_triangles) {
    const int V = target_triangles >= 300000 ? 64 : 32;
    const int U = std::max(8, int(target_triangles / (2 * std::size_t(V))));
    const double p = 2, q = 3, R = 1.0, rt = 0.45, tube = 0.14, scale = 14.0;
    ngi::TriangleMesh m;
    m.positions.reserve(std::size_t(U) * V);
    m.normals.reserve(std::size_t(U) * V);
    for (int i = 0; i < U; ++i) {
        const double f = 2.0 * M_PI * i / U, cq = std::cos(q * f), sq = std::sin(q * f), cp = std::cos(p * f),
                     sp = std::sin(p * f);
        const glm::dvec3 C((R + rt * cq) * cp, (R + rt * cq) * sp, rt * sq);
        const glm::dvec3 T = glm::normalize(glm::dvec3(-rt * q * sq * cp - p * (R + rt * cq) * sp,
                                                       -rt * q * sq * sp + p * (R + rt * cq) * cp, rt * q * cq));
        const glm::dvec3 N(cq * cp, cq * sp, sq), B = glm::cross(T, N);
        for (int k = 0; k < V; ++k) {
            const double th = 2.0 * M_PI * k / V;
            const glm::dvec3 radial = std::cos(th) * N + std::sin(th) * B;
            m.positions.push_back(glm::vec3(scale * (C + tube * radial)));
            m.normals.push_back(glm::vec3(radial));
        }
    }
    for (int i = 0; i < U; ++i)
        for (int k = 0; k < V; ++k) {
            const unsigned a = unsigned(i * V + k), b = unsigned(i * V + (k + 1) % V),
                           c = unsigned(((i + 1) % U) * V + k), d = unsigned(((i + 1) % U) * V + (k + 1) % V);
            m.triangles.push_back({a, c, d});
            m.triangles.push_back({a, d, b});
        }
    m.materials.assign(m.triangles.size(), 1);
    return m;
}

struct NamedMesh {
    std::string name, source;
    ngi::TriangleMesh mesh;
};

// nullopt-like: an empty name means "skip" (the reason in source).
NamedMesh make_mesh(const std::string& spec, const std::string& bunny) {
    if (spec.rfind("tube:", 0) == 0) {
        const std::size_t n = std::stoul(spec.substr(5));
        NamedMesh m{"", "bench_bvh torus-knot tube", torus_knot_tube(n)};
        m.name = "tube_" + std::to_string(m.mesh.triangle_count());
        return m;
    }
    if (spec == "bunny" || spec.rfind("file:", 0) == 0) {
        const std::string path = spec == "bunny" ? bunny : spec.substr(5);
        if (path.empty() || !std::ifstream(path)) return {"", spec + ": no file " + path + " (tools/fetch_bunny.sh writes it)", {}};
        ngi::LoadedMesh lm = ngi::load_mesh(path);
        return {spec == "bunny" ? "bunny" : path, path, std::move(lm.mesh)};
    }
    try {
        ngi::VoxelScene scene = ngi::make_scene(spec);
        if (!scene.mesh.empty()) return {spec, "ngi::make_scene(\"" + spec + "\").mesh", std::move(scene.mesh)};
        std::fprintf(stderr, "bench_bvh: scene %s has no triangles; using tube:100000 instead\n", spec.c_str());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_bvh: scene %s unavailable (%s); using tube:100000 instead\n", spec.c_str(), e.what());
    }
    NamedMesh m = make_mesh("tube:100000", bunny);
    m.source += " (stand-in for " + spec + ")";
    return m;
}

// ---- rays ------------------------------------------------------------------------------------------------------

std::uint64_t mix(std::uint64_t x) {  // splitmix64's finalizer: a deterministic per-ray random stream
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}
float u01(std::uint64_t h) { return float(h >> 40) * (1.0f / 16777216.0f); }

void push_ray(std::vector<float>& rays, glm::vec3 o, glm::vec3 d, float tmax) {
    rays.insert(rays.end(), {o.x, o.y, o.z, tmax, d.x, d.y, d.z, 0.0f});
}

std::vector<float> primary_rays(const ngi::TriangleMesh& mesh, int size, float zoom) {
    const auto [lo, hi] = ngi::mesh_bounds(mesh);
    const glm::vec3 centre = 0.5f * (lo + hi);
    const float half_fov = 20.0f * kPi / 180.0f;
    const glm::vec3 fwd = glm::normalize(glm::vec3(-0.55f, -0.35f, -0.76f));
    const glm::vec3 right = glm::normalize(glm::cross(fwd, glm::vec3(0, 1, 0))), up = glm::cross(right, fwd);
    // Back off until the bounding box's nearest face plane (across the view) spans the field of view.
    float ex = 0, ez = 0;
    for (int k = 0; k < 8; ++k) {
        const glm::vec3 c((k & 1 ? hi : lo).x, (k & 2 ? hi : lo).y, (k & 4 ? hi : lo).z);
        ex = std::max({ex, std::abs(glm::dot(c - centre, right)), std::abs(glm::dot(c - centre, up))});
        ez = std::max(ez, std::abs(glm::dot(c - centre, fwd)));
    }
    const glm::vec3 eye = centre - fwd * (ez + ex / std::tan(half_fov));
    const float s = std::tan(half_fov) * zoom;
    std::vector<float> rays;
    rays.reserve(std::size_t(size) * size * 8);
    for (int ty = 0; ty < size; ty += 4)
        for (int tx = 0; tx < size; tx += 4)
            for (int y = ty; y < std::min(ty + 4, size); ++y)
                for (int x = tx; x < std::min(tx + 4, size); ++x) {
                    const float px = ((x + 0.5f) / size * 2.0f - 1.0f) * s, py = (1.0f - (y + 0.5f) / size * 2.0f) * s;
                    push_ray(rays, eye, glm::normalize(fwd + px * right + py * up), kTmax);
                }
    return rays;
}

struct Surface {
    glm::vec3 p, n;  // point on the triangle, geometric normal facing the incoming ray
};

std::vector<Surface> hit_points(const ngi::TriangleMesh& mesh, const std::vector<float>& rays,
                                const std::vector<RayHit>& hits) {
    std::vector<Surface> out;
    for (std::size_t i = 0; i < hits.size(); ++i) {
        if (hits[i].prim < 0) continue;
        const glm::uvec3 t = mesh.triangles[std::size_t(hits[i].prim)];
        const glm::vec3 a = mesh.positions[t.x], b = mesh.positions[t.y], c = mesh.positions[t.z];
        glm::vec3 n = glm::normalize(glm::cross(b - a, c - a));
        const glm::vec3 d(rays[8 * i + 4], rays[8 * i + 5], rays[8 * i + 6]);
        if (glm::dot(n, d) > 0) n = -n;
        out.push_back({(1.0f - hits[i].u - hits[i].v) * a + hits[i].u * b + hits[i].v * c, n});
    }
    return out;
}

std::vector<float> bounce_rays(const std::vector<Surface>& pts, float eps) {
    std::vector<float> rays;
    rays.reserve(pts.size() * 8);
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const glm::vec3 n = pts[i].n;
        const glm::vec3 t = glm::normalize(std::abs(n.x) > 0.5f ? glm::cross(n, glm::vec3(0, 1, 0)) : glm::cross(n, glm::vec3(1, 0, 0)));
        const glm::vec3 b = glm::cross(n, t);
        const std::uint64_t h = mix(i * 2 + 0x1234), h2 = mix(h);
        const float r = std::sqrt(u01(h)), phi = 2.0f * kPi * u01(h2);
        const glm::vec3 d = glm::normalize(r * std::cos(phi) * t + r * std::sin(phi) * b + std::sqrt(std::max(0.0f, 1.0f - r * r)) * n);
        push_ray(rays, pts[i].p + eps * n, d, kTmax);
    }
    return rays;
}

const glm::vec3 kLight = glm::normalize(glm::vec3(0.35f, 0.85f, 0.40f));

std::vector<float> shadow_rays(const std::vector<Surface>& pts, float eps) {
    std::vector<float> rays;
    for (const Surface& s : pts)
        if (glm::dot(s.n, kLight) > 0) push_ray(rays, s.p + eps * s.n, kLight, kTmax);
    return rays;
}

// ---- Embree ----------------------------------------------------------------------------------------------------

struct EmbreeMemory {
    std::atomic<long long> bytes{0};
};

bool memory_monitor(void* user, ssize_t bytes, bool) {
    static_cast<EmbreeMemory*>(user)->bytes.fetch_add(bytes);
    return true;
}

struct Embree {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    EmbreeMemory memory;
    long long bvh_bytes = 0;  // what the commit allocated (the BVH with its leaf triangles)

    Embree(const std::string& config) {
        device = rtcNewDevice(config.c_str());
        if (!device) throw std::runtime_error("rtcNewDevice(\"" + config + "\") failed: " + std::to_string(rtcGetDeviceError(nullptr)));
        rtcSetDeviceMemoryMonitorFunction(device, memory_monitor, &memory);
    }
    ~Embree() {
        if (scene) rtcReleaseScene(scene);
        rtcReleaseDevice(device);
    }
    Embree(const Embree&) = delete;
    Embree& operator=(const Embree&) = delete;

    // Returns the commit's (build's) wall time in ms.
    double build(const ngi::TriangleMesh& mesh, RTCBuildQuality quality) {
        if (scene) rtcReleaseScene(scene);
        scene = rtcNewScene(device);
        rtcSetSceneFlags(scene, RTC_SCENE_FLAG_NONE);
        rtcSetSceneBuildQuality(scene, quality);
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        rtcSetGeometryBuildQuality(g, quality);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                             3 * sizeof(float), mesh.positions.size()));
        auto* ix = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                 3 * sizeof(unsigned), mesh.triangles.size()));
        std::memcpy(v, mesh.positions.data(), mesh.positions.size() * 12);
        std::memcpy(ix, mesh.triangles.data(), mesh.triangles.size() * 12);
        rtcCommitGeometry(g);
        rtcAttachGeometry(scene, g);
        rtcReleaseGeometry(g);
        const long long before = memory.bytes.load();
        const double t0 = now_ms();
        rtcCommitScene(scene);
        const double ms = now_ms() - t0;
        bvh_bytes = memory.bytes.load() - before;
        if (rtcGetDeviceError(device) != RTC_ERROR_NONE) throw std::runtime_error("Embree build failed");
        return ms;
    }
};

// Embree's own statistics of the tree it builds (BVH type, builder, node counts, depth, the single-ray
// intersector): printed by a build with verbose=2, on a separate device, captured from stdout (not timed).
json embree_tree_stats(const ngi::TriangleMesh& mesh, RTCBuildQuality quality, int threads) {
    std::fflush(stdout);
    std::cout.flush();
    char path[] = "/tmp/bench_bvh_embree_XXXXXX";
    const int fd = mkstemp(path);
    if (fd < 0) return {};
    const int saved = dup(1);
    dup2(fd, 1);
    {
        Embree e("threads=" + std::to_string(threads) + ",verbose=2");
        e.build(mesh, quality);
    }
    std::fflush(stdout);
    std::cout.flush();
    dup2(saved, 1);
    close(saved);
    close(fd);
    std::ifstream f(path);
    const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    unlink(path);
    json j;
    std::smatch m;
    if (std::regex_search(text, m, std::regex(R"(building (\S+) using (\S+))"))) {
        j["bvh"] = m[1].str();
        j["builder"] = m[2].str();
    }
    if (std::regex_search(text, m, std::regex(R"(depth = (\d+))"))) j["depth"] = std::stoi(m[1].str());
    if (std::regex_search(text, m, std::regex(R"(getAABBNodes\s*:.*#nodes =\s*(\d+))")))
        j["interior_nodes"] = std::stol(m[1].str());
    if (std::regex_search(text, m, std::regex(R"(leaves\s*:.*#nodes =\s*(\d+))"))) j["leaves"] = std::stol(m[1].str());
    if (std::regex_search(text, m, std::regex(R"(total\s*:.*#bytes =\s*([0-9.]+) MB)"))) j["tree_mb"] = std::stod(m[1].str());
    if (std::regex_search(text, m, std::regex(R"(selected scene intersector\s*intersector1\s*=\s*(\S+))")))
        j["intersector1"] = m[1].str();
    return j;
}

RTCRayHit embree_rayhit(const float* r) {
    RTCRayHit rh;
    rh.ray.org_x = r[0]; rh.ray.org_y = r[1]; rh.ray.org_z = r[2];
    rh.ray.tnear = 0.0f;
    rh.ray.dir_x = r[4]; rh.ray.dir_y = r[5]; rh.ray.dir_z = r[6];
    rh.ray.time = 0.0f;
    rh.ray.tfar = r[3];
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    return rh;
}

// Packet types by width.
template <int W> struct Packet;
template <> struct Packet<4> {
    using Hit = RTCRayHit4; using Ray = RTCRay4;
    static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, Hit* h) { rtcIntersect4(v, s, c, h); }
    static void occluded(const int* v, RTCScene s, RTCIntersectContext* c, Ray* r) { rtcOccluded4(v, s, c, r); }
};
template <> struct Packet<8> {
    using Hit = RTCRayHit8; using Ray = RTCRay8;
    static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, Hit* h) { rtcIntersect8(v, s, c, h); }
    static void occluded(const int* v, RTCScene s, RTCIntersectContext* c, Ray* r) { rtcOccluded8(v, s, c, r); }
};
template <> struct Packet<16> {
    using Hit = RTCRayHit16; using Ray = RTCRay16;
    static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, Hit* h) { rtcIntersect16(v, s, c, h); }
    static void occluded(const int* v, RTCScene s, RTCIntersectContext* c, Ray* r) { rtcOccluded16(v, s, c, r); }
};

template <class RayT>
void fill_packet_ray(RayT& p, int k, const float* r) {
    p.org_x[k] = r[0]; p.org_y[k] = r[1]; p.org_z[k] = r[2];
    p.tnear[k] = 0.0f;
    p.dir_x[k] = r[4]; p.dir_y[k] = r[5]; p.dir_z[k] = r[6];
    p.time[k] = 0.0f;
    p.tfar[k] = r[3];
    p.mask[k] = 0xFFFFFFFFu;
    p.id[k] = 0;
    p.flags[k] = 0;
}

// Runs f(begin, end) over [0, count) in chunks from a shared counter on `threads` threads (1 = this thread).
// Returns the wall time in ms.
double parallel(int threads, std::size_t count, const std::function<void(std::size_t, std::size_t)>& f) {
    constexpr std::size_t chunk = 1024;  // a multiple of every packet width
    std::atomic<std::size_t> next{0};
    auto worker = [&] {
        for (;;) {
            const std::size_t b = next.fetch_add(chunk);
            if (b >= count) break;
            f(b, std::min(count, b + chunk));
        }
    };
    const double t0 = now_ms();
    if (threads <= 1) worker();
    else {
        std::vector<std::thread> ts;
        for (int i = 0; i < threads; ++i) ts.emplace_back(worker);
        for (auto& t : ts) t.join();
    }
    return now_ms() - t0;
}

// One Embree traversal variant over a ray set: closest (RayHit per ray) or any hit (prim 0 = occluded, -1 = not).
double embree_trace(RTCScene scene, const std::vector<float>& rays, bool any, int width, int threads, bool coherent,
                    std::vector<RayHit>& out) {
    const std::size_t count = rays.size() / 8;
    out.assign(count, RayHit{});
    auto single = [&](std::size_t b, std::size_t e) {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        if (coherent) ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        for (std::size_t i = b; i < e; ++i) {
            RTCRayHit rh = embree_rayhit(&rays[8 * i]);
            if (any) {
                rtcOccluded1(scene, &ctx, &rh.ray);
                out[i].prim = rh.ray.tfar < 0.0f ? 0 : -1;
            } else {
                rtcIntersect1(scene, &ctx, &rh);
                if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID)
                    out[i] = {rh.ray.tfar, std::int32_t(rh.hit.primID), rh.hit.u, rh.hit.v};
            }
        }
    };
    auto packets = [&](auto width_tag, std::size_t b, std::size_t e) {
        constexpr int W = decltype(width_tag)::value;
        using P = Packet<W>;
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        if (coherent) ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        alignas(64) int valid[W];
        alignas(64) typename P::Hit ph;
        for (std::size_t i = b; i < e; i += W) {
            for (int k = 0; k < W; ++k) {
                valid[k] = i + k < e ? -1 : 0;
                fill_packet_ray(ph.ray, k, &rays[8 * std::min(i + k, e - 1)]);
                ph.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
                ph.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
            }
            if (any) {
                P::occluded(valid, scene, &ctx, &ph.ray);
                for (int k = 0; k < W && i + k < e; ++k) out[i + k].prim = ph.ray.tfar[k] < 0.0f ? 0 : -1;
            } else {
                P::intersect(valid, scene, &ctx, &ph);
                for (int k = 0; k < W && i + k < e; ++k)
                    if (ph.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID)
                        out[i + k] = {ph.ray.tfar[k], std::int32_t(ph.hit.primID[k]), ph.hit.u[k], ph.hit.v[k]};
            }
        }
    };
    switch (width) {
        case 1: return parallel(threads, count, single);
        case 4: return parallel(threads, count, [&](std::size_t b, std::size_t e) { packets(std::integral_constant<int, 4>{}, b, e); });
        case 8: return parallel(threads, count, [&](std::size_t b, std::size_t e) { packets(std::integral_constant<int, 8>{}, b, e); });
        case 16: return parallel(threads, count, [&](std::size_t b, std::size_t e) { packets(std::integral_constant<int, 16>{}, b, e); });
    }
    throw std::runtime_error("packet width " + std::to_string(width));
}

// ---- statistics ------------------------------------------------------------------------------------------------

json times(std::vector<double> ms, std::size_t rays) {
    std::sort(ms.begin(), ms.end());
    const double med = ms[ms.size() / 2], mn = ms.front();
    return {{"median_ms", med}, {"min_ms", mn}, {"mrays_per_s_median", double(rays) / (med * 1e3)},
            {"mrays_per_s_best", double(rays) / (mn * 1e3)}, {"all_ms", ms}};
}

double median_of(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

// ngi (a) against Embree (b), the same rays. Rays on which they disagree (hit/miss, or t by 1e-4 or more; the
// first 200) are settled by the host's brute-force watertight reference (every triangle tested): which of the two
// (a = ngi, b = Embree) found the reference's answer.
json agreement(const std::vector<RayHit>& a, const std::vector<RayHit>& b, bool any, const ngi::TriangleMesh* mesh = nullptr,
               const std::vector<float>* rays = nullptr) {
    std::size_t hit_miss = 0, both = 0, t_over = 0, prim_diff = 0;
    double max_rel = 0;
    std::vector<std::size_t> disputed;
    auto rel = [](double x, double y) { return std::abs(x - y) / std::max(1e-30, std::abs(y)); };
    for (std::size_t i = 0; i < a.size(); ++i) {
        const bool ha = a[i].prim >= 0, hb = b[i].prim >= 0;
        if (ha != hb) {
            ++hit_miss;
            disputed.push_back(i);
            continue;
        }
        if (!ha || any) continue;
        ++both;
        const double r = rel(a[i].t, b[i].t);
        max_rel = std::max(max_rel, r);
        if (r >= 1e-4) {
            ++t_over;
            disputed.push_back(i);
        }
        if (a[i].prim != b[i].prim) ++prim_diff;
    }
    json j = {{"rays", a.size()}, {"hit_miss_disagreements", hit_miss},
              {"hit_miss_disagreement_rate", a.empty() ? 0.0 : double(hit_miss) / double(a.size())}};
    if (!any) {
        j["both_hit"] = both;
        j["t_max_rel_diff"] = max_rel;
        j["t_rel_diff_over_1e-4"] = t_over;
        j["different_triangle"] = prim_diff;  // same t (< 1e-4): a shared edge or vertex, either answer is right
    }
    if (mesh && rays && !disputed.empty()) {
        std::size_t checked = 0, a_right = 0, b_right = 0;
        for (std::size_t i : disputed) {
            if (checked == 200) break;
            ++checked;
            const float* r = &(*rays)[8 * i];
            const RayHit ref = ngi::detail::intersect_brute_force(*mesh, {r[0], r[1], r[2]}, {r[4], r[5], r[6]}, r[3]);
            auto right = [&](const RayHit& h) {
                if ((h.prim >= 0) != (ref.prim >= 0)) return false;
                return h.prim < 0 || any || rel(h.t, ref.t) < 1e-4;
            };
            a_right += right(a[i]);
            b_right += right(b[i]);
        }
        j["disputed_checked_by_brute_force"] = checked;
        j["disputed_ngi_right"] = a_right;
        j["disputed_embree_right"] = b_right;
    }
    return j;
}

std::size_t hit_count(const std::vector<RayHit>& h) {
    return std::size_t(std::count_if(h.begin(), h.end(), [](const RayHit& x) { return x.prim >= 0; }));
}

}  // namespace

int main(int argc, char** argv) {
    try {
        const auto device_specs = split(arg(argc, argv, "--devices", arg(argc, argv, "--device", "pocl")));
        const auto mesh_specs = split(arg(argc, argv, "--meshes", "knot:seed=1,bunny,tube:1000000"));
        const char* assets = std::getenv("NGI_ASSET_DIR");
        // tools/fetch_bunny.sh's default: $NGI_ASSET_DIR, else the user's cache directory.
        const char* xdg = std::getenv("XDG_CACHE_HOME");
        const char* home = std::getenv("HOME");
        const std::string cache = xdg && *xdg ? std::string(xdg) : std::string(home && *home ? home : ".") + "/.cache";
        const std::string bunny =
            arg(argc, argv, "--bunny", (assets && *assets ? std::string(assets) : cache + "/ngi/assets") + "/bunny.obj");
        const auto ray_sets = split(arg(argc, argv, "--rays", "primary,bounce,shadow"));
        const int size = std::stoi(arg(argc, argv, "--size", "512"));
        const int repeats = std::max(1, std::stoi(arg(argc, argv, "--repeats", "9")));
        const int threads = std::max(1, std::stoi(arg(argc, argv, "--threads", "2")));
        const std::string quality_name = arg(argc, argv, "--quality", "high");
        const std::string out_path = arg(argc, argv, "--out", "");
        if (quality_name != "high" && quality_name != "medium") throw std::runtime_error("--quality high|medium");
        const RTCBuildQuality quality = quality_name == "high" ? RTC_BUILD_QUALITY_HIGH : RTC_BUILD_QUALITY_MEDIUM;

        std::vector<ngi::Device> devices;
        for (const auto& s : device_specs) devices.push_back(ngi::Device::open(s));

        Embree embree("threads=" + std::to_string(threads));
        // The packet width Embree runs natively on this CPU (8 on AVX2, 16 on AVX-512).
        const int width = rtcGetDeviceProperty(embree.device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) ? 16
                          : rtcGetDeviceProperty(embree.device, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED) ? 8 : 4;

        json out = {{"benchmark", "bench_bvh"},
                    {"size", size},
                    {"repeats", repeats},
                    {"threads", threads},
                    {"hardware_threads", std::thread::hardware_concurrency()},
                    {"loadavg_start", loadavg()},
                    {"embree", {{"version", RTC_VERSION_STRING}, {"scene_flags", "RTC_SCENE_FLAG_NONE"},
                                {"build_quality", quality_name == "high" ? "RTC_BUILD_QUALITY_HIGH" : "RTC_BUILD_QUALITY_MEDIUM"},
                                {"packet_width", width}}},
                    {"devices", json::array()},
                    {"meshes", json::array()},
                    {"skipped", json::array()}};
        for (const auto& d : devices) out["devices"].push_back(d.info().name);

        for (const auto& spec : mesh_specs) {
            NamedMesh nm = make_mesh(spec, bunny);
            if (nm.name.empty()) {
                std::fprintf(stderr, "bench_bvh: skipping %s\n", nm.source.c_str());
                out["skipped"].push_back(nm.source);
                continue;
            }
            const ngi::TriangleMesh& mesh = nm.mesh;
            const auto [lo, hi] = ngi::mesh_bounds(mesh);
            const float eps = 1e-5f * glm::length(hi - lo);
            std::fprintf(stderr, "%s: %zu triangles (%s)\n", nm.name.c_str(), mesh.triangle_count(), nm.source.c_str());

            // Builds: ngi once per round of three, Embree likewise (median), and Embree on one thread once.
            std::vector<double> ngi_build_ms, embree_build_ms;
            ngi::detail::Bvh bvh;
            for (int k = 0; k < 3; ++k) {
                const double t0 = now_ms();
                bvh = ngi::detail::build_bvh(mesh);
                ngi_build_ms.push_back(now_ms() - t0);
            }
            double embree_build_1t_ms = 0;
            {
                Embree one("threads=1");
                embree_build_1t_ms = one.build(mesh, quality);
            }
            const json tree_stats = embree_tree_stats(mesh, quality, threads);
            for (int k = 0; k < 3; ++k) embree_build_ms.push_back(embree.build(mesh, quality));

            struct DeviceState {
                ngi::detail::DeviceBvh bvh;
                double setup_ms;
            };
            std::vector<DeviceState> dev;
            for (auto& d : devices) {
                const double t0 = now_ms();
                ngi::detail::DeviceBvh db(d, bvh);
                dev.push_back({std::move(db), now_ms() - t0});
            }

            // Ray sets: primary first (the others start from its hits, as ngi's first device found them).
            float zoom = 1.0f, best_fraction = -1.0f;
            for (float z : {1.0f, 0.85f, 0.7f, 0.55f, 0.4f}) {
                std::vector<RayHit> probe;
                const std::vector<float> rays = primary_rays(mesh, 64, z);
                embree_trace(embree.scene, rays, false, 1, 1, true, probe);
                const float fraction = float(hit_count(probe)) / float(probe.size());
                if (fraction > best_fraction) { best_fraction = fraction; zoom = z; }
                if (fraction >= 0.5f) break;
            }
            const std::vector<float> primary = primary_rays(mesh, size, zoom);
            std::vector<RayHit> primary_hits = dev.at(0).bvh.trace(primary, false);
            const std::vector<Surface> pts = hit_points(mesh, primary, primary_hits);

            json mesh_json = {{"mesh", nm.name}, {"source", nm.source}, {"triangles", mesh.triangle_count()},
                              {"vertices", mesh.positions.size()}, {"camera_zoom", zoom},
                              {"ngi_bvh", {{"build_ms_median", median_of(ngi_build_ms)}, {"build_ms_all", ngi_build_ms},
                                           {"nodes", bvh.node_count()}, {"depth", bvh.depth},
                                           {"bytes", bvh.nodes.size() * 4 + bvh.tri_vertices.size() * 4},
                                           {"max_leaf", ngi::detail::kBvhMaxLeaf}}},
                              {"embree_bvh", {{"build_ms_median", median_of(embree_build_ms)}, {"build_ms_all", embree_build_ms},
                                              {"build_threads", threads}, {"build_ms_1_thread", embree_build_1t_ms},
                                              {"bytes", embree.bvh_bytes}, {"tree", tree_stats}}}};
            for (std::size_t d = 0; d < dev.size(); ++d)
                mesh_json["ngi_bvh"]["upload_and_compile_ms_" + device_specs[d]] = dev[d].setup_ms;

            for (const auto& set : ray_sets) {
                const bool any = set == "shadow";
                std::vector<float> rays;
                if (set == "primary") rays = primary;
                else if (set == "bounce") rays = bounce_rays(pts, eps);
                else if (set == "shadow") rays = shadow_rays(pts, eps);
                else throw std::runtime_error("unknown ray set " + set);
                const std::size_t count = rays.size() / 8;
                if (count == 0) continue;
                const bool coherent = set == "primary";

                // Warm-up and results: each ngi device once (steps), Embree's variants once.
                std::vector<std::vector<RayHit>> ngi_hits(dev.size());
                std::vector<double> mean_steps(dev.size());
                for (std::size_t d = 0; d < dev.size(); ++d) {
                    std::vector<std::uint32_t> steps;
                    ngi_hits[d] = dev[d].bvh.trace(rays, any, &steps);
                    double sum = 0;
                    for (auto s : steps) sum += s;
                    mean_steps[d] = sum / double(count);
                }
                struct Variant { std::string name; int width, threads; };
                const std::string single = any ? "rtcOccluded1" : "rtcIntersect1";
                const std::string packet = std::string(any ? "rtcOccluded" : "rtcIntersect") + std::to_string(width);
                std::vector<Variant> variants = {{single + " 1 thread", 1, 1},
                                                 {single + " " + std::to_string(threads) + " threads", 1, threads},
                                                 {packet + " " + std::to_string(threads) + " threads", width, threads}};
                std::vector<std::vector<RayHit>> embree_hits(variants.size());
                for (std::size_t v = 0; v < variants.size(); ++v)
                    embree_trace(embree.scene, rays, any, variants[v].width, variants[v].threads, coherent, embree_hits[v]);

                // Timed rounds: every tracer once per round.
                std::vector<std::vector<double>> dev_ms(dev.size()), call_ms(dev.size()), emb_ms(variants.size());
                std::vector<RayHit> scratch;
                for (int r = 0; r < repeats; ++r) {
                    for (std::size_t d = 0; d < dev.size(); ++d) {
                        double device_ms = 0;
                        const double t0 = now_ms();
                        scratch = dev[d].bvh.trace(rays, any, nullptr, &device_ms);
                        call_ms[d].push_back(now_ms() - t0);
                        dev_ms[d].push_back(device_ms);
                    }
                    for (std::size_t v = 0; v < variants.size(); ++v)
                        emb_ms[v].push_back(embree_trace(embree.scene, rays, any, variants[v].width, variants[v].threads,
                                                         coherent, scratch));
                }

                json c = {{"mesh", nm.name}, {"triangles", mesh.triangle_count()}, {"rays", set}, {"any_hit", any},
                          {"count", count}, {"hit_fraction", double(hit_count(embree_hits[0])) / double(count)},
                          {"ngi", json::array()}, {"embree", json::array()}};
                for (std::size_t v = 0; v < variants.size(); ++v)
                    c["embree"].push_back({{"variant", variants[v].name}, {"time", times(emb_ms[v], count)},
                                           {"agrees_with_single_ray", agreement(embree_hits[v], embree_hits[0], any)}});
                const double emb_1t = median_of(emb_ms[0]), emb_nt = median_of(emb_ms[1]), emb_pk = median_of(emb_ms[2]);
                for (std::size_t d = 0; d < dev.size(); ++d) {
                    const double dm = median_of(dev_ms[d]), cm = median_of(call_ms[d]);
                    json n = {{"device", device_specs[d]}, {"device_name", devices[d].info().name},
                              {"device_time", times(dev_ms[d], count)}, {"call_time", times(call_ms[d], count)},
                              {"mean_steps_per_ray", mean_steps[d]},
                              // Throughput ratios ngi / Embree (> 1: ngi faster), medians; the target is 0.3.
                              {"ratio_device_vs_embree_single_ray_mt", emb_nt / dm},
                              {"ratio_device_vs_embree_single_ray_1t", emb_1t / dm},
                              {"ratio_device_vs_embree_packets_mt", emb_pk / dm},
                              {"ratio_call_vs_embree_single_ray_mt", emb_nt / cm},
                              {"agreement_with_embree", agreement(ngi_hits[d], embree_hits[0], any, &mesh, &rays)}};
                    c["ngi"].push_back(n);
                    const json& ag = n["agreement_with_embree"];
                    std::fprintf(stderr,
                                 "%-14s %-7s %8zu rays  ngi[%s] %6.2f Mrays/s device (%6.2f call), %5.1f steps/ray | "
                                 "Embree %6.2f (1T) %6.2f (%dT) %6.2f (x%d %dT) | ngi/Embree(%dT) %.2f | "
                                 "hit/miss diff %zu, t>1e-4 %s%s\n",
                                 nm.name.c_str(), set.c_str(), count, device_specs[d].c_str(), count / (dm * 1e3),
                                 count / (cm * 1e3), mean_steps[d], count / (emb_1t * 1e3), count / (emb_nt * 1e3),
                                 threads, count / (emb_pk * 1e3), width, threads, threads, emb_nt / dm,
                                 ag["hit_miss_disagreements"].get<std::size_t>(),
                                 any ? "-" : std::to_string(ag["t_rel_diff_over_1e-4"].get<std::size_t>()).c_str(),
                                 ag.contains("disputed_checked_by_brute_force")
                                     ? (" (brute force: ngi right " + ag["disputed_ngi_right"].dump() + ", Embree right " +
                                        ag["disputed_embree_right"].dump() + " of " +
                                        ag["disputed_checked_by_brute_force"].dump() + ")").c_str()
                                     : "");
                }
                mesh_json["cases"].push_back(c);
            }
            out["meshes"].push_back(mesh_json);
        }
        out["loadavg_end"] = loadavg();
        const std::string text = out.dump(2);
        std::printf("%s\n", text.c_str());
        if (!out_path.empty()) std::ofstream(out_path) << text << "\n";
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_bvh: %s\n", e.what());
        return 1;
    }
}
