#include "light_bake.hpp"

#include <ngi/error.hpp>

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include "voxel_dda.hpp"

namespace ngi_gl {
namespace {

constexpr float kPi = 3.14159265358979f;
constexpr float kRayOffset = 1e-3f;  // pathtrace.cl RAY_OFFSET

float radical_inverse(std::uint32_t i) {
    i = (i << 16) | (i >> 16);
    i = ((i & 0x55555555u) << 1) | ((i & 0xAAAAAAAAu) >> 1);
    i = ((i & 0x33333333u) << 2) | ((i & 0xCCCCCCCCu) >> 2);
    i = ((i & 0x0F0F0F0Fu) << 4) | ((i & 0xF0F0F0F0u) >> 4);
    i = ((i & 0x00FF00FFu) << 8) | ((i & 0xFF00FF00u) >> 8);
    return float(i) * 2.3283064365386963e-10f;
}

std::uint32_t hash(std::uint32_t x) {  // lowbias32 (Wellons): the per-texel rotation of the point set
    x ^= x >> 16; x *= 0x7feb352du; x ^= x >> 15; x *= 0x846ca68bu; x ^= x >> 16;
    return x;
}

float luminance(glm::vec3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

struct Emitter {
    ExposedFace face;
    glm::vec3 radiance;
    bool lamp;
    QuadCorners corners;
};

// (1/pi) * integral of cos over the solid angle of the polygon seen from p, clipped to n's hemisphere: the form
// factor from a point to a polygon, (1 / 2 pi) |sum_i theta_i n . unit(v_i x v_i+1)| (Lambert).
float polygon_form_factor(glm::vec3 p, glm::vec3 n, const glm::vec3* poly, int count) {
    glm::vec3 clipped[8];
    int m = 0;
    for (int i = 0; i < count; ++i) {  // Sutherland-Hodgman against the plane n . (x - p) = 0
        const glm::vec3 a = poly[i], b = poly[(i + 1) % count];
        const float da = glm::dot(a - p, n), db = glm::dot(b - p, n);
        if (da > 0.0f) clipped[m++] = a;
        if ((da > 0.0f) != (db > 0.0f)) clipped[m++] = a + (b - a) * (da / (da - db));
    }
    if (m < 3) return 0.0f;
    glm::vec3 sum(0.0f);
    for (int i = 0; i < m; ++i) {
        const glm::vec3 a = glm::normalize(clipped[i] - p), b = glm::normalize(clipped[(i + 1) % m] - p);
        const glm::vec3 c = glm::cross(a, b);
        const float len = glm::length(c);
        if (len < 1e-12f) continue;
        sum += std::acos(glm::clamp(glm::dot(a, b), -1.0f, 1.0f)) * (c / len);
    }
    return std::abs(glm::dot(sum, n)) / (2.0f * kPi);
}

glm::vec3 emitter_light(const ngi::VoxelScene& scene, const Emitter& e, glm::vec3 p, glm::vec3 n, long long& rays) {
    const glm::vec3 ne = face_normal(e.face.face);
    if (glm::dot(p - e.corners.p[0], ne) <= 0.0f) return glm::vec3(0.0f);  // behind its emitting side
    const float ff = polygon_form_factor(p, n, e.corners.p, 4);
    if (luminance(e.radiance) * ff < 1e-5f) return glm::vec3(0.0f);
    // Visibility: 3 x 3 points on the emitter, each weighted by its share of the form factor.
    const int a = e.face.face >> 1, a1 = (a + 1) % 3, a2 = (a + 2) % 3;
    float wsum = 0.0f, vsum = 0.0f;
    for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) {
            glm::vec3 q = e.corners.p[0];
            q[a1] = float(e.face.cell[a1]) + (i + 0.5f) / 3.0f;
            q[a2] = float(e.face.cell[a2]) + (j + 0.5f) / 3.0f;
            glm::vec3 w = q - p;
            const float d = glm::length(w);
            w /= d;
            const float cx = glm::dot(n, w), cl = -glm::dot(ne, w);
            if (cx <= 0.0f || cl <= 0.0f) continue;
            const float weight = cx * cl / (d * d);
            wsum += weight;
            ++rays;
            const DdaHit h = dda_trace(scene, p, w, d + 1.0f);
            if (h.hit && h.cell == e.face.cell && h.face == e.face.face) vsum += weight;
        }
    return wsum > 0.0f ? e.radiance * (ff * vsum / wsum) : glm::vec3(0.0f);
}

}  // namespace

LightBake bake_static_light(const ngi::VoxelScene& scene, const std::vector<ExposedFace>& faces,
                            const ngi::Lighting& lighting, const BakeSettings& settings) {
    const auto t0 = std::chrono::steady_clock::now();
    LightBake b;
    b.k = settings.texels > 0 ? settings.texels : (faces.size() <= 20000 ? 4 : faces.size() <= 100000 ? 2 : 1);
    const double rays = double(faces.size()) * b.k * b.k * std::max(settings.sky_rays, 1);
    if (rays > double(kMaxBakeRays))
        throw ngi::InputError("light bake: " + std::to_string(faces.size()) + " faces x " + std::to_string(b.k) + "^2 texels x " +
                              std::to_string(settings.sky_rays) + " sky rays = " + std::to_string((long long)rays) +
                              " rays, beyond the " + std::to_string(kMaxBakeRays) +
                              " one bake may trace (~30 s); lower --bake-rays or --bake-texels");
    const std::size_t count = std::max<std::size_t>(faces.size(), 1);
    b.tiles_per_row = int(std::ceil(std::sqrt(double(count))));
    b.width = b.tiles_per_row * b.k;
    b.height = int((count + b.tiles_per_row - 1) / b.tiles_per_row) * b.k;
    b.sky_static.assign(std::size_t(b.width) * b.height * 3, 0.0f);
    b.lamps.assign(b.sky_static.size(), 0.0f);

    std::vector<Emitter> emitters;
    for (const ExposedFace& f : faces) {
        const ngi::Material& m = scene.palette[f.mat];
        if (m.emission.x + m.emission.y + m.emission.z > 0.0f)
            emitters.push_back({f, m.emission, m.lamp, quad_corners(f)});
    }
    const int rays_per_texel = std::max(settings.sky_rays, 1);
    std::atomic<std::size_t> next{0};
    std::atomic<long long> total_rays{0};
    auto worker = [&] {
        long long rays = 0;
        for (std::size_t fi; (fi = next.fetch_add(64)) < faces.size();) {
            for (std::size_t i = fi; i < std::min(fi + 64, faces.size()); ++i) {
                const ExposedFace& f = faces[i];
                const glm::vec3 n = face_normal(f.face);
                const int a = f.face >> 1, a1 = (a + 1) % 3, a2 = (a + 2) % 3;
                glm::vec3 t1(0.0f), t2(0.0f);  // tangents for the cosine-weighted directions
                t1[a1] = 1.0f;
                t2[a2] = 1.0f;
                const glm::vec2 tile = b.tile_origin(i);
                for (int tj = 0; tj < b.k; ++tj)
                    for (int ti = 0; ti < b.k; ++ti) {
                        glm::vec3 p(f.cell);
                        p[a] += (f.face & 1) ? 0.0f : 1.0f;
                        p[a1] += (ti + 0.5f) / b.k;
                        p[a2] += (tj + 0.5f) / b.k;
                        p += n * kRayOffset;
                        const std::uint32_t seed = hash(std::uint32_t(i) * 131u + std::uint32_t(tj * b.k + ti));
                        const float ru = float(seed & 0xFFFFu) / 65536.0f, rv = float(seed >> 16) / 65536.0f;
                        glm::vec3 sky(0.0f);
                        for (int r = 0; r < rays_per_texel; ++r) {
                            float u = (r + 0.5f) / rays_per_texel + ru, v = radical_inverse(std::uint32_t(r)) + rv;
                            u -= std::floor(u);
                            v -= std::floor(v);
                            const float rad = std::sqrt(u), phi = 2.0f * kPi * v;
                            const glm::vec3 w = glm::normalize(t1 * (rad * std::cos(phi)) + t2 * (rad * std::sin(phi)) +
                                                               n * std::sqrt(std::max(0.0f, 1.0f - u)));
                            ++rays;
                            if (!dda_trace(scene, p, w).hit) sky += ngi::sky_radiance(lighting.sky, lighting.sun, w);
                        }
                        glm::vec3 stat = sky / float(rays_per_texel), lamp(0.0f);
                        for (const Emitter& e : emitters) {
                            const glm::vec3 l = emitter_light(scene, e, p, n, rays);
                            (e.lamp ? lamp : stat) += l;
                        }
                        const std::size_t o =
                            ((std::size_t(tile.y) + tj) * std::size_t(b.width) + std::size_t(tile.x) + ti) * 3;
                        for (int c = 0; c < 3; ++c) {
                            b.sky_static[o + c] = stat[c];
                            b.lamps[o + c] = lamp[c];
                        }
                    }
            }
        }
        total_rays += rays;
    };
    const int threads = settings.threads > 0 ? settings.threads : int(std::max(1u, std::thread::hardware_concurrency()));
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
    worker();
    for (auto& t : pool) t.join();
    b.rays = total_rays;
    b.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return b;
}

}  // namespace ngi_gl
