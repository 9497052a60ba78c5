// The path tracer's light transport against analytic answers: white furnace, a sun-lit plane with a shadow,
// the sky model, convergence rate, determinism, and the reference (bounces = 0) against the direct feature.
#include <catch2/catch.hpp>
#include <cmath>

#include "ngi/camera.hpp"
#include "ngi/render.hpp"
#include "ngi/scene.hpp"
#include "test_support.hpp"

using namespace ngi;

namespace {

Lighting dark() { return Lighting{}; }  // no sun, black sky, lamps off

// A closed box: walls of one material around an empty (size-2)^3 interior.
VoxelScene closed_box(int size, Material wall) {
    VoxelScene s({size, size, size}, "box");
    const auto m = s.add_material(wall);
    s.fill({0, 0, 0}, {size, size, size}, m);
    s.fill({1, 1, 1}, {size - 1, size - 1, size - 1}, 0);
    return s;
}

struct Stats {
    double mean = 0, stderr_ = 0;
};

// Mean over the pixels of channel c and the standard error of that mean (pixels are independent estimates; the
// channels of one pixel are not, so each channel is pooled on its own).
Stats pooled(const Image& mean, const Image& var, int c) {
    Stats s;
    double v = 0;
    const std::size_t n = mean.plane();
    for (std::size_t i = c * n; i < (c + 1) * n; ++i) {
        s.mean += mean.data[i];
        v += var.data[i];
    }
    s.mean /= double(n);
    s.stderr_ = std::sqrt(v) / double(n);
    return s;
}

}  // namespace

TEST_CASE("white furnace: closed box of albedo a and emission E has lighting E / (1 - a)", "[render]") {
    const float a = 0.5f, E = 0.75f;
    const VoxelScene box = closed_box(6, {glm::vec3(a), glm::vec3(E), false});
    Renderer r(test::device(), box);
    RenderSettings rs;
    rs.feature_spp = 8;  // noise is fine here: these checks are not about light quality
    rs.n = 16;
    rs.reference_spp = 64;
    rs.max_bounces = 1000;  // Russian roulette ends the paths; the cap is never the reason to stop
    rs.seed = 7;
    const CameraPose pose{{3.0f, 3.0f, 3.0f}, glm::normalize(glm::vec3(0.3f, -0.2f, -1.0f)), {0, 1, 0}};
    Image var;
    double expected = E / (1.0 - a);
    if (const long limit = test::ctx().loop_limit(); limit > 0) {
        // A driver that ends loops after `limit` iterations (llvmpipe) cannot bound a 1000-bounce path: the
        // renderer refuses it rather than truncate it silently. 20 bounces fit, and lose a^21 of the energy.
        CHECK_THROWS_WITH(r.render_reference(pose, dark(), rs, &var), Catch::Contains("loop iterations"));
        WARN("loop limit " << limit << " on " << test::device().info().name << ": furnace with 20 bounces, not 1000");
        rs.max_bounces = 20;
        expected = E * (1.0 - std::pow(double(a), 21)) / (1.0 - a);
    }
    const Image ref = r.render_reference(pose, dark(), rs, &var);
    for (int c = 0; c < 3; ++c) {
        const Stats s = pooled(ref, var, c);
        INFO("channel " << c << ": mean " << s.mean << " +- " << s.stderr_ << ", expected " << expected);
        CHECK(std::abs(s.mean - expected) < 4.0 * s.stderr_);
        CHECK(s.stderr_ < 0.01 * expected);
    }
    // Per pixel: within 4 standard errors almost everywhere (the estimate is a sum of many samples).
    int outliers = 0;
    for (std::size_t i = 0; i < ref.data.size(); ++i)
        outliers += std::abs(ref.data[i] - expected) > 4.0 * std::sqrt(var.data[i]);
    CHECK(outliers <= int(ref.data.size()) / 100);

    // The direct feature sees the emission of the walls only: E everywhere; final = albedo * ref + emission.
    rs.feature_spp = 64;
    rs.reference = false;
    const Frame fr = r.render(pose, dark(), rs);
    double direct = 0, albedo = 0, emission = 0;
    std::size_t cnt = 0;
    for (int f = 0; f < kFaceCount; ++f)
        for (std::size_t i = 0; i < fr.get(Feature::Direct, Face(f)).data.size(); ++i, ++cnt) {
            direct += fr.get(Feature::Direct, Face(f)).data[i];
            albedo += fr.get(Feature::Albedo, Face(f)).data[i];
            emission += fr.get(Feature::Emission, Face(f)).data[i];
        }
    CHECK(direct / cnt == Approx(E).epsilon(0.01));
    CHECK(albedo / cnt == Approx(a).epsilon(1e-6));
    CHECK(emission / cnt == Approx(E).epsilon(1e-6));
}

TEST_CASE("sun-lit plane: direct = E cos(theta) / pi, zero in the shadow of a pillar, and the sky matches the host model",
          "[render][oclgrind-small]") {
    VoxelScene s({12, 6, 12}, "plane");
    s.fill({0, 0, 0}, {12, 1, 12}, s.add_material({glm::vec3(0.5f), glm::vec3(0.0f), false}));
    const glm::ivec3 p_lo(7, 1, 5), p_hi(8, 4, 6);  // a pillar
    s.fill(p_lo, p_hi, s.add_material({glm::vec3(0.3f), glm::vec3(0.0f), false}));

    const float theta = glm::radians(35.0f);
    Lighting l = lighting_at(11.0f, 0.0f);  // a real sky for the env check, sun replaced below
    l.sun.direction = {-0.8f * std::sin(theta), std::cos(theta), 0.6f * std::sin(theta)};  // unit, 35 deg from up
    l.sun.irradiance = {2.0f, 1.5f, 1.0f};
    l.sun.angular_radius = 0.0f;
    const Sky sky = l.sky;
    l.sky = Sky{};  // sky off while checking the sun alone

    Renderer r(test::device(), s);
    RenderSettings rs;
    rs.feature_spp = 8;  // noise is fine here: these checks are not about light quality
    rs.n = 24;
    rs.feature_spp = 1;
    rs.reference = false;
    const CameraPose pose{{4.5f, 2.5f, 4.5f}, {0, 0, -1}, {0, 1, 0}};
    Frame fr = r.render(pose, l, rs);

    const CameraCluster cl = CameraCluster::from_look_up(pose.look, pose.up);
    // Host ray / box test for the pillar's shadow; `grow` enlarges (> 0) or shrinks (< 0) the box.
    auto blocked = [&](glm::vec3 o, glm::vec3 d, float grow) {
        float t0 = 0, t1 = 1e30f;
        for (int k = 0; k < 3; ++k) {
            const float ta = (float(p_lo[k]) - grow - o[k]) / d[k], tb = (float(p_hi[k]) + grow - o[k]) / d[k];
            t0 = std::max(t0, std::min(ta, tb));
            t1 = std::min(t1, std::max(ta, tb));
        }
        return t0 <= t1;
    };
    int lit = 0, shadowed = 0, checked = 0;
    for (int f = 0; f < kFaceCount; ++f) {
        const FaceBasis b = cl.face(Face(f));
        const Image& alb = fr.get(Feature::Albedo, Face(f));
        const Image& dir = fr.get(Feature::Direct, Face(f));
        for (int row = 0; row < rs.n; ++row)
            for (int col = 0; col < rs.n; ++col) {
                const glm::vec3 d = glm::normalize(face_pixel_direction(b, col, row, rs.n));
                if (d.y >= -1e-3f || alb.at(0, row, col) != 0.5f) continue;  // floor pixels only
                const glm::vec3 p = pose.position + d * ((1.0f - pose.position.y) / d.y);
                const glm::vec3 q = p + glm::vec3(0, 1e-3f, 0);
                const bool shade = blocked(q, l.sun.direction, 0.0f);
                if (blocked(q, l.sun.direction, 0.02f) != blocked(q, l.sun.direction, -0.02f)) continue;  // edge
                for (int c = 0; c < 3; ++c) {
                    const float expected = shade ? 0.0f : l.sun.irradiance[c] * std::cos(theta) / 3.14159265f;
                    REQUIRE(dir.at(c, row, col) == Approx(expected).margin(1e-5).epsilon(1e-4));
                }
                ++checked;
                (shade ? shadowed : lit)++;
            }
    }
    CHECK(checked > 500);
    CHECK(shadowed > 5);
    CHECK(lit > 400);

    // Sky pixels: env equals the host's sky model (sun disc excluded), everything else 0.
    l.sky = sky;
    fr = r.render(pose, l, rs);
    int sky_pixels = 0;
    for (int f = 0; f < kFaceCount; ++f) {
        const FaceBasis b = cl.face(Face(f));
        const Image& env = fr.get(Feature::Env, Face(f));
        const Image& depth = fr.get(Feature::Depth, Face(f));
        for (int row = 0; row < rs.n; ++row)
            for (int col = 0; col < rs.n; ++col) {
                const glm::vec3 d = glm::normalize(face_pixel_direction(b, col, row, rs.n));
                if (depth.at(0, row, col) < 1e4f) {
                    CHECK(env.at(0, row, col) == 0.0f);
                    continue;
                }
                const glm::vec3 e = sky_radiance(l.sky, l.sun, d);
                for (int c = 0; c < 3; ++c) REQUIRE(env.at(c, row, col) == Approx(e[c]).epsilon(1e-4));
                ++sky_pixels;
            }
    }
    CHECK(sky_pixels > 1000);
}

TEST_CASE("reference error falls like 1/sqrt(spp) and the same seed gives identical frames", "[render]") {
    const float a = 0.6f, E = 0.5f;
    VoxelScene box = closed_box(6, {glm::vec3(a), glm::vec3(E), false});
    box.set({0, 3, 3}, 0);  // a window: sun and sky come in, and the furnace no longer has a closed form
    box.set({1, 3, 3}, 0);
    box.fill({2, 1, 2}, {3, 2, 3}, box.add_material({{0.8f, 0.2f, 0.1f}, glm::vec3(0.0f), false}));
    Renderer r(test::device(), box);
    const Lighting l = lighting_at(10.0f, 1.5f);
    const CameraPose pose{{3.5f, 3.2f, 3.5f}, {0, -0.3f, -1}, {0, 1, 0}};
    RenderSettings rs;
    rs.feature_spp = 8;  // noise is fine here: these checks are not about light quality
    rs.n = 12;
    rs.reference_spp = 4096;
    rs.seed = 1000;
    const Image truth = r.render_reference(pose, l, rs);

    std::vector<double> logn, loge;
    for (int spp : {4, 16, 64, 256}) {
        double se = 0;
        const int reps = 4;  // average the squared error over seeds: a steadier estimate of the RMS error
        for (int k = 0; k < reps; ++k) {
            rs.reference_spp = spp;
            rs.seed = std::uint32_t(k + 1);
            const Image est = r.render_reference(pose, l, rs);
            for (std::size_t i = 0; i < est.data.size(); ++i) se += std::pow(double(est.data[i]) - truth.data[i], 2.0);
        }
        logn.push_back(std::log(double(spp)));
        loge.push_back(0.5 * std::log(se / reps / double(truth.data.size())));
    }
    // Least-squares slope of log(rms error) against log(spp).
    const double mx = (logn[0] + logn[1] + logn[2] + logn[3]) / 4, my = (loge[0] + loge[1] + loge[2] + loge[3]) / 4;
    double sxy = 0, sxx = 0;
    for (int i = 0; i < 4; ++i) {
        sxy += (logn[i] - mx) * (loge[i] - my);
        sxx += (logn[i] - mx) * (logn[i] - mx);
    }
    const double slope = sxy / sxx;
    INFO("slope " << slope);
    CHECK(slope == Approx(-0.5).margin(0.1));

    rs.reference_spp = 8;
    rs.seed = 42;
    const Frame f1 = r.render(pose, l, rs), f2 = r.render(pose, l, rs);
    CHECK(f1.reference->data == f2.reference->data);
    for (int f = 0; f < kFeatureCount; ++f)
        for (int face = 0; face < kFaceCount; ++face) CHECK(f1.faces[f][face].data == f2.faces[f][face].data);
    rs.seed = 43;
    const Frame f3 = r.render(pose, l, rs);
    CHECK(f3.reference->data != f1.reference->data);
    CHECK(f3.get(Feature::Albedo, Face::Front).data == f1.get(Feature::Albedo, Face::Front).data);
}

TEST_CASE("reference with bounces = 0 equals the direct feature in expectation (sun, sky and lamps)", "[render]") {
    VoxelScene room = closed_box(8, {glm::vec3(0.6f), glm::vec3(0.0f), false});
    room.fill({0, 3, 2}, {1, 5, 5}, 0);  // window in the -x wall
    room.fill({3, 7, 3}, {5, 8, 4}, 0);  // hole in the roof
    room.set({6, 6, 6}, room.add_material({glm::vec3(0.9f), {4.0f, 3.0f, 2.0f}, true}));        // lamp
    room.set({1, 1, 6}, room.add_material({glm::vec3(0.5f), {0.5f, 2.0f, 3.0f}, false}));       // glowing block
    Lighting l = lighting_at(17.6f, 2.8f);  // low sun, twilight sky, lamps partly on
    REQUIRE(l.lamp_level > 0.0f);
    REQUIRE(l.sun.irradiance.r > 0.0f);
    Renderer r(test::device(), room);
    RenderSettings rs;
    rs.feature_spp = 8;  // noise is fine here: these checks are not about light quality
    rs.n = 16;
    rs.feature_spp = 256;
    rs.reference_spp = 256;
    rs.max_bounces = 0;
    rs.reference_face = Face::Front;
    rs.seed = 5;
    const CameraPose pose{{4.5f, 4.0f, 4.5f}, {-1, -0.2f, 0.3f}, {0, 1, 0}};
    Image var;
    const Image ref = r.render_reference(pose, l, rs, &var);
    rs.reference = false;
    const Frame fr = r.render(pose, l, rs);
    const Image& direct = fr.get(Feature::Direct, Face::Front);
    int outliers = 0;
    for (std::size_t i = 0; i < ref.data.size(); ++i)
        outliers += std::abs(ref.data[i] - direct.data[i]) > 4.0 * std::sqrt(2.0 * var.data[i]) + 1e-6;
    for (int c = 0; c < 3; ++c) {  // per channel: pixels are independent, the channels of a pixel are not
        double diff = 0, v = 0;
        for (std::size_t i = c * ref.plane(); i < (c + 1) * ref.plane(); ++i) {
            diff += double(ref.data[i]) - direct.data[i];
            v += 2.0 * var.data[i];  // two independent estimates of the same quantity with the same spp
        }
        INFO("channel " << c << ": sum of differences " << diff << ", its standard error " << std::sqrt(v));
        CHECK(std::abs(diff) < 4.0 * std::sqrt(v));
    }
    CHECK(outliers <= int(ref.data.size()) / 50);
}

TEST_CASE("sky portals: same expectation as cosine sampling alone, lower variance", "[render]") {
    VoxelScene room = closed_box(9, {glm::vec3(0.7f), glm::vec3(0.0f), false});
    room.fill({0, 0, 0}, {9, 1, 9}, 0);
    room.fill({0, 0, 0}, {9, 1, 9}, room.add_material({glm::vec3(0.3f), glm::vec3(0.0f), false}));
    room.fill({3, 2, 0}, {6, 5, 1}, 0);  // window in the -z wall
    room.fill({8, 2, 5}, {9, 4, 7}, 0);  // a second one in the +x wall
    room.fill({2, 1, 5}, {4, 3, 7}, room.add_material({{0.8f, 0.3f, 0.1f}, glm::vec3(0.0f), false}));
    Lighting l = lighting_at(12.0f, 0.5f);
    l.sun.irradiance = glm::vec3(0.0f);  // the sky alone
    Renderer r(test::device(), room);
    RenderSettings rs;
    rs.feature_spp = 8;  // noise is fine here: these checks are not about light quality
    rs.n = 16;
    rs.reference_spp = 128;
    rs.seed = 11;
    const CameraPose pose{{4.5f, 3.5f, 5.5f}, {0.2f, -0.3f, 1.0f}, {0, 1, 0}};  // looking away from the window
    Image var_on, var_off;
    const Image on = r.render_reference(pose, l, rs, &var_on);
    rs.sky_portals = false;
    const Image off = r.render_reference(pose, l, rs, &var_off);
    double v_on = 0, v_off = 0;
    for (int c = 0; c < 3; ++c) {
        const Stats a = pooled(on, var_on, c), b = pooled(off, var_off, c);
        INFO("channel " << c << ": portals " << a.mean << " +- " << a.stderr_ << ", cosine only " << b.mean << " +- "
                        << b.stderr_);
        CHECK(std::abs(a.mean - b.mean) < 4.0 * std::hypot(a.stderr_, b.stderr_));
        v_on += a.stderr_ * a.stderr_;
        v_off += b.stderr_ * b.stderr_;
    }
    INFO("variance of the mean: portals " << v_on << ", cosine only " << v_off);
    CHECK(v_on < 0.5 * v_off);
}

TEST_CASE("sunlit patches: same expectation as cosine sampling alone, lower variance", "[render]") {
    VoxelScene room = closed_box(10, {glm::vec3(0.6f), glm::vec3(0.0f), false});
    room.fill({0, 3, 3}, {1, 7, 7}, 0);  // a window in the -x wall; the sun shines in onto the floor
    room.fill({6, 1, 2}, {8, 3, 4}, room.add_material({{0.2f, 0.7f, 0.2f}, glm::vec3(0.0f), false}));
    Lighting l;  // the sun alone, low in the -x direction
    l.sun.direction = glm::normalize(glm::vec3(-1.0f, 0.8f, 0.1f));
    l.sun.irradiance = {3.0f, 2.8f, 2.5f};
    l.sun.angular_radius = 0.01f;
    Renderer r(test::device(), room);
    RenderSettings rs;
    rs.feature_spp = 8;  // noise is fine here: these checks are not about light quality
    rs.n = 16;
    rs.reference_spp = 128;
    rs.seed = 21;
    const CameraPose pose{{4.5f, 5.0f, 5.0f}, {1.0f, -0.2f, 0.3f}, {0, 1, 0}};  // the lit patch is behind
    Image var_on, var_off;
    const Image on = r.render_reference(pose, l, rs, &var_on);
    rs.sunlit_patches = false;
    const Image off = r.render_reference(pose, l, rs, &var_off);
    double v_on = 0, v_off = 0;
    for (int c = 0; c < 3; ++c) {
        const Stats a = pooled(on, var_on, c), b = pooled(off, var_off, c);
        INFO("channel " << c << ": patches " << a.mean << " +- " << a.stderr_ << ", cosine only " << b.mean << " +- "
                        << b.stderr_);
        CHECK(a.mean > 0.01);
        CHECK(std::abs(a.mean - b.mean) < 4.0 * std::hypot(a.stderr_, b.stderr_));
        v_on += a.stderr_ * a.stderr_;
        v_off += b.stderr_ * b.stderr_;
    }
    INFO("variance of the mean: patches " << v_on << ", cosine only " << v_off);
    CHECK(v_on < 0.5 * v_off);
}
