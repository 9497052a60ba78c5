// Seeded procedural voxel scenes (families: room, street, cave, backlit, bleed, sculpture, cornell, cornell_pink; the
// mesh families knot, superquadric and blob are built in mesh_procedural.cpp). Deterministic across platforms:
// std::mt19937 is fully specified; distributions are our own (the standard ones are implementation-defined).
#include <algorithm>
#include <cmath>
#include <glm/gtc/constants.hpp>

#include "ngi/error.hpp"
#include "ngi/scene.hpp"
#include "render/mesh_scene.hpp"
#include "render/rand.hpp"

namespace ngi {
namespace {

using detail::Rand;

// Linear-RGB albedos of the block kinds (roughly Minecraft-like), varied a little per scene.
const glm::vec3 kStone(0.42f, 0.42f, 0.41f), kDarkStone(0.20f, 0.20f, 0.21f), kPlaster(0.72f, 0.70f, 0.65f),
    kWood(0.50f, 0.34f, 0.18f), kDarkWood(0.24f, 0.15f, 0.08f), kBrick(0.52f, 0.21f, 0.14f),
    kGrass(0.20f, 0.42f, 0.11f), kDirt(0.34f, 0.24f, 0.15f), kAsphalt(0.10f, 0.10f, 0.11f),
    kPavement(0.50f, 0.49f, 0.47f), kLeaves(0.13f, 0.36f, 0.08f), kRoof(0.42f, 0.14f, 0.09f),
    kMetal(0.15f, 0.15f, 0.16f), kWhite(0.80f, 0.80f, 0.78f), kSand(0.70f, 0.62f, 0.42f);
const std::vector<glm::vec3> kWool = {{0.70f, 0.07f, 0.05f}, {0.09f, 0.55f, 0.10f}, {0.08f, 0.14f, 0.65f},
                                      {0.80f, 0.68f, 0.08f}, {0.80f, 0.35f, 0.05f}, {0.50f, 0.10f, 0.55f},
                                      {0.08f, 0.50f, 0.55f}, {0.80f, 0.80f, 0.78f}};
const glm::vec3 kLampAlbedo(0.90f, 0.85f, 0.70f), kLampLight(6.0f, 4.6f, 2.8f);

std::uint8_t add(VoxelScene& s, Rand& r, glm::vec3 albedo, glm::vec3 emission = glm::vec3(0.0f), bool lamp = false) {
    const glm::vec3 a = glm::clamp(albedo * r.range(0.9f, 1.1f), glm::vec3(0.0f), glm::vec3(0.95f));
    return s.add_material({a, emission, lamp});
}

// Box of blocks [lo, hi) with hollow interior: walls of `wall`, floor slab at lo.y and roof at hi.y - 1.
void shell(VoxelScene& s, glm::ivec3 lo, glm::ivec3 hi, std::uint8_t wall, std::uint8_t floor, std::uint8_t roof) {
    s.fill(lo, hi, wall);
    s.fill(lo + glm::ivec3(1, 1, 1), hi - glm::ivec3(1, 1, 1), 0);
    s.fill({lo.x, lo.y, lo.z}, {hi.x, lo.y + 1, hi.z}, floor);
    s.fill({lo.x, hi.y - 1, lo.z}, {hi.x, hi.y, hi.z}, roof);
}

// A rectangular hole (or panel of `m`) in the wall plane of a room: wall 0 = -z, 1 = +z, 2 = -x, 3 = +x.
// `along` and `y` are the lower corner within the wall, relative to the room's interior corner.
void wall_rect(VoxelScene& s, glm::ivec3 in_lo, glm::ivec3 in_hi, int wall, int along, int y, int w, int h,
               std::uint8_t m) {
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            const int yy = in_lo.y + y + j;
            glm::ivec3 c;
            if (wall == 0) c = {in_lo.x + along + i, yy, in_lo.z - 1};
            else if (wall == 1) c = {in_lo.x + along + i, yy, in_hi.z};
            else if (wall == 2) c = {in_lo.x - 1, yy, in_lo.z + along + i};
            else c = {in_hi.x, yy, in_lo.z + along + i};
            s.set(c, m);
        }
}

int wall_length(glm::ivec3 in_lo, glm::ivec3 in_hi, int wall) {
    return wall < 2 ? in_hi.x - in_lo.x : in_hi.z - in_lo.z;
}

// Furniture on the floor of the interior [in_lo, in_hi): tables, shelves, sofas, carpets, pillars.
void furnish(VoxelScene& s, Rand& r, glm::ivec3 in_lo, glm::ivec3 in_hi, int pieces) {
    const int H = in_hi.y - in_lo.y;
    const std::uint8_t wood = add(s, r, kWood), dark = add(s, r, kDarkWood);
    auto spot = [&](int w, int d) {
        return glm::ivec3(r.irange(in_lo.x, std::max(in_lo.x, in_hi.x - w)), in_lo.y,
                          r.irange(in_lo.z, std::max(in_lo.z, in_hi.z - d)));
    };
    if (r.chance(0.6f)) {  // carpet: coloured floor patch
        const int w = r.irange(2, 5), d = r.irange(2, 5);
        const glm::ivec3 p = spot(w, d);
        s.fill({p.x, p.y - 1, p.z}, {p.x + w, p.y, p.z + d}, add(s, r, r.pick(kWool)));
    }
    for (int k = 0; k < pieces; ++k) {
        switch (r.irange(0, 3)) {
            case 0: {  // table: four legs and a top
                const int w = r.irange(2, 3), d = 2;
                const glm::ivec3 p = spot(w, d);
                for (int dx : {0, w - 1})
                    for (int dz : {0, d - 1}) s.set(p + glm::ivec3(dx, 0, dz), dark);
                s.fill(p + glm::ivec3(0, 1, 0), p + glm::ivec3(w, 2, d), wood);
                break;
            }
            case 1: {  // shelf against a wall
                const int h = std::max(1, std::min(H - 1, r.irange(2, 3)));
                const bool along_x = r.chance(0.5f);
                const int len = r.irange(1, 3);
                glm::ivec3 p = along_x ? glm::ivec3(r.irange(in_lo.x, in_hi.x - len), in_lo.y, r.chance(0.5f) ? in_lo.z : in_hi.z - 1)
                                       : glm::ivec3(r.chance(0.5f) ? in_lo.x : in_hi.x - 1, in_lo.y, r.irange(in_lo.z, in_hi.z - len));
                s.fill(p, p + (along_x ? glm::ivec3(len, h, 1) : glm::ivec3(1, h, len)), wood);
                break;
            }
            case 2: {  // sofa / bed: a coloured block
                const bool along_x = r.chance(0.5f);
                const int w = along_x ? r.irange(2, 3) : r.irange(1, 2), d = along_x ? r.irange(1, 2) : r.irange(2, 3);
                const glm::ivec3 p = spot(w, d);
                s.fill(p, p + glm::ivec3(w, 1, d), add(s, r, r.pick(kWool)));
                break;
            }
            default: {  // pillar, floor to ceiling
                const glm::ivec3 p = spot(1, 1);
                s.fill(p, p + glm::ivec3(1, H, 1), add(s, r, kStone));
                break;
            }
        }
    }
}

// Lamps set into the ceiling above the interior.
void ceiling_lamps(VoxelScene& s, Rand& r, glm::ivec3 in_lo, glm::ivec3 in_hi, int count) {
    const std::uint8_t lamp = add(s, r, kLampAlbedo, kLampLight, true);
    for (int k = 0; k < count; ++k)
        s.set({r.irange(in_lo.x, in_hi.x - 1), in_hi.y, r.irange(in_lo.z, in_hi.z - 1)}, lamp);
}

void set_region(VoxelScene& s, glm::vec3 lo, glm::vec3 hi) {
    s.camera.region_lo = lo;
    s.camera.region_hi = hi;
}

// ---- room: one or two rooms with windows, a door, holes; outdoors around it ----------------------------------
VoxelScene room(std::uint32_t seed) {
    Rand r(seed, 1);
    const int W = r.irange(8, 16), D = r.irange(8, 16), H = r.irange(4, 6), M = 4;
    VoxelScene s({W + 2 + 2 * M, H + 2, D + 2 + 2 * M}, "room");
    s.fill({0, 0, 0}, {s.size.x, 1, s.size.z}, add(s, r, kGrass));
    const std::vector<glm::vec3> walls = {kPlaster, kWood, kBrick, kStone, kSand};
    const std::uint8_t wall = add(s, r, r.pick(walls)), floor = add(s, r, r.chance(0.5f) ? kWood : kStone),
                       ceil = add(s, r, kPlaster);
    const glm::ivec3 lo(M, 0, M), hi(M + W + 2, H + 2, M + D + 2), in_lo = lo + 1, in_hi = hi - 1;
    shell(s, lo, hi, wall, floor, ceil);
    if (W >= 10 && r.chance(0.4f)) {  // partition wall with a doorway
        const int x = in_lo.x + W / 2;
        s.fill({x, in_lo.y, in_lo.z}, {x + 1, in_hi.y, in_hi.z}, wall);
        const int z = r.irange(in_lo.z, in_hi.z - 2);
        s.fill({x, in_lo.y, z}, {x + 1, in_lo.y + std::min(3, H), z + 2}, 0);
    }
    furnish(s, r, in_lo, in_hi, r.irange(2, 6));
    int windows = 0;
    for (int w = 0; w < 4; ++w) {
        for (int k = r.irange(0, 2); k > 0; --k, ++windows) {
            const int len = wall_length(in_lo, in_hi, w), ww = r.irange(2, 4), wh = r.irange(2, std::min(3, H - 1));
            wall_rect(s, in_lo, in_hi, w, r.irange(1, len - ww - 1), r.irange(1, H - wh), ww, wh, 0);
        }
    }
    if (windows < 2) wall_rect(s, in_lo, in_hi, windows == 0 ? 1 : 0, 2, 1, 3, 2, 0);  // at least some daylight
    const int door_wall = r.irange(0, 3), door_w = r.irange(1, 2);
    wall_rect(s, in_lo, in_hi, door_wall, r.irange(1, wall_length(in_lo, in_hi, door_wall) - door_w - 1), 0, door_w,
              std::min(3, H - 1), 0);
    for (int k = r.chance(0.5f) ? r.irange(1, 3) : 0; k > 0; --k) {  // broken blocks
        const int w = r.irange(0, 3);
        wall_rect(s, in_lo, in_hi, w, r.irange(0, wall_length(in_lo, in_hi, w) - 1), r.irange(0, H - 1), 1, 1, 0);
    }
    if (r.chance(0.4f)) {  // hole in the roof
        const int w = r.irange(1, 3), d = r.irange(1, 3);
        const int x = r.irange(in_lo.x, in_hi.x - w), z = r.irange(in_lo.z, in_hi.z - d);
        s.fill({x, in_hi.y, z}, {x + w, in_hi.y + 1, z + d}, 0);
    }
    ceiling_lamps(s, r, in_lo, in_hi, r.irange(1, 4));
    set_region(s, glm::vec3(in_lo) + glm::vec3(0.6f, 1.3f, 0.6f), glm::vec3(in_hi) - glm::vec3(0.6f, 0.7f, 0.6f));
    s.sun_azimuth = r.range(0.0f, glm::two_pi<float>());
    s.default_time = r.range(9.0f, 16.0f);
    return s;
}

// ---- street: road, pavements, houses on both sides, street lamps, trees -----------------------------------------
VoxelScene street(std::uint32_t seed) {
    Rand r(seed, 2);
    const int X = r.irange(48, 64), Z = 36, Y = 18, zc = Z / 2;
    VoxelScene s({X, Y, Z}, "street");
    s.fill({0, 0, 0}, {X, 1, Z}, add(s, r, kGrass));
    s.fill({0, 0, zc - 3}, {X, 1, zc + 3}, add(s, r, kAsphalt));
    const std::uint8_t line = add(s, r, kWhite), pave = add(s, r, kPavement);
    for (int x = 1; x < X; x += 4) s.fill({x, 0, zc}, {x + 2, 1, zc + 1}, line);
    s.fill({0, 0, zc - 5}, {X, 1, zc - 3}, pave);
    s.fill({0, 0, zc + 3}, {X, 1, zc + 5}, pave);

    const std::vector<glm::vec3> wall_colours = {kPlaster, kBrick, kWood, kStone, kSand, {0.55f, 0.50f, 0.35f}};
    const std::uint8_t roof = add(s, r, kRoof), floor = add(s, r, kWood);
    const std::uint8_t lamp = add(s, r, kLampAlbedo, kLampLight, true), metal = add(s, r, kMetal);
    for (int side = 0; side < 2; ++side) {
        for (int x = r.irange(1, 3); x + 6 < X - 1;) {
            const int w = std::min(r.irange(6, 10), X - 1 - x), d = r.irange(6, 9), h = r.irange(4, 8),
                      back = r.irange(1, 3);
            const int z0 = side == 0 ? zc - 5 - back - d : zc + 5 + back;
            const glm::ivec3 lo(x, 0, z0), hi(x + w, h + 1, z0 + d);
            shell(s, lo, hi, add(s, r, r.pick(wall_colours)), floor, roof);
            if (r.chance(0.5f)) {  // gable roof rising along z
                for (int k = 1; z0 + k < z0 + d - k; ++k)
                    s.fill({x, h + k, z0 + k}, {x + w, h + k + 1, z0 + d - k}, roof);
            }
            const glm::ivec3 in_lo = lo + 1, in_hi = hi - 1;
            const int front = side == 0 ? 1 : 0;  // the wall facing the road
            for (int storey = 0; storey * 3 + 2 < h - 1; ++storey)
                for (int wall = 0; wall < 4; ++wall) {
                    const int len = wall_length(in_lo, in_hi, wall);
                    for (int a = 1; a + 1 < len; a += 3)
                        if (r.chance(0.7f)) wall_rect(s, in_lo, in_hi, wall, a, storey * 3 + 1, 1, 2, 0);
                }
            wall_rect(s, in_lo, in_hi, front, (w - 2) / 2, 0, 1, 2, 0);  // door
            if (r.chance(0.6f)) s.set({x + w / 2, h, z0 + d / 2}, lamp);   // ceiling light: lit windows at night
            x += w + r.irange(1, 3);
        }
    }
    for (int side = 0; side < 2; ++side)  // street lamps on the pavements
        for (int x = r.irange(2, 6); x < X - 1; x += r.irange(8, 12)) {
            const int z = side == 0 ? zc - 4 : zc + 4;
            s.fill({x, 1, z}, {x + 1, 5, z + 1}, metal);
            s.set({x, 5, z}, lamp);
        }
    const std::uint8_t trunk = add(s, r, kDarkWood), leaves = add(s, r, kLeaves);
    for (int k = 0, trees = r.irange(3, 8); k < 200 && trees > 0; ++k) {
        const glm::ivec3 base(r.irange(2, X - 3), 1, r.chance(0.5f) ? r.irange(2, zc - 7) : r.irange(zc + 6, Z - 3));
        const int th = r.irange(3, 4);
        bool free = true;  // the tree's box must be empty (no house)
        for (int z = base.z - 2; z <= base.z + 2 && free; ++z)
            for (int y = 1; y <= th + 2 && free; ++y)
                for (int x = base.x - 2; x <= base.x + 2 && free; ++x) free = !s.solid({x, y, z});
        if (!free) continue;
        for (int z = -2; z <= 2; ++z)
            for (int y = -2; y <= 2; ++y)
                for (int x = -2; x <= 2; ++x)
                    if (x * x + y * y + z * z <= 5) s.set(base + glm::ivec3(x, th + y, z), leaves);
        s.fill(base, base + glm::ivec3(1, th, 1), trunk);
        --trees;
    }
    set_region(s, {2.0f, 1.5f, zc - 4.5f}, {X - 2.0f, 4.5f, zc + 4.5f});
    s.sun_azimuth = r.range(0.0f, glm::two_pi<float>());
    s.default_time = r.range(9.0f, 17.0f);
    return s;
}

// ---- cave: worm tunnels through layered rock, mine corridors with timber frames, shafts to the sky, crystals ---
VoxelScene cave(std::uint32_t seed) {
    Rand r(seed, 3);
    const int X = 40, Y = 24, Z = 40;
    VoxelScene s({X, Y, Z}, "cave");
    s.fill({0, 0, 0}, {X, Y, Z}, add(s, r, kStone));
    s.fill({0, Y - 3, 0}, {X, Y - 1, Z}, add(s, r, kDirt));
    s.fill({0, Y - 1, 0}, {X, Y, Z}, add(s, r, kGrass));
    const std::vector<glm::vec3> rocks = {{0.50f, 0.30f, 0.24f}, {0.62f, 0.62f, 0.60f}, {0.12f, 0.12f, 0.12f},
                                          {0.40f, 0.36f, 0.28f}};
    for (int k = 0; k < 30; ++k) {  // veins of other rock
        const std::uint8_t m = add(s, r, r.pick(rocks));
        const glm::ivec3 c(r.irange(0, X - 1), r.irange(0, Y - 5), r.irange(0, Z - 1));
        const int rad = r.irange(1, 2);
        for (int z = -rad; z <= rad; ++z)
            for (int y = -rad; y <= rad; ++y)
                for (int x = -rad; x <= rad; ++x)
                    if (x * x + y * y + z * z <= rad * rad && s.solid(c + glm::ivec3(x, y, z))) s.set(c + glm::ivec3(x, y, z), m);
    }
    auto carve = [&](glm::vec3 c, float rad) {
        const int ri = int(std::ceil(rad));
        for (int z = -ri; z <= ri; ++z)
            for (int y = -ri; y <= ri; ++y)
                for (int x = -ri; x <= ri; ++x) {
                    const glm::ivec3 v = glm::ivec3(glm::floor(c)) + glm::ivec3(x, y, z);
                    if (v.y < 1 || v.y > Y - 5 || v.x < 1 || v.z < 1 || v.x > X - 2 || v.z > Z - 2) continue;
                    if (glm::length(glm::vec3(v) + 0.5f - c) < rad) s.set(v, 0);
                }
    };
    std::vector<glm::vec3> points;
    for (int wi = 0, worms = r.irange(3, 5); wi < worms; ++wi) {
        glm::vec3 p(r.range(8, X - 8), r.range(5, Y - 9), r.range(8, Z - 8));
        float yaw = r.range(0.0f, glm::two_pi<float>()), pitch = 0.0f, rad = r.range(1.6f, 2.4f);
        for (int k = 0, steps = r.irange(50, 110); k < steps; ++k) {
            carve(p, rad);
            points.push_back(p);
            yaw += r.range(-0.35f, 0.35f);
            pitch = std::clamp(pitch + r.range(-0.15f, 0.15f), -0.3f, 0.3f);
            rad = std::clamp(rad + r.range(-0.2f, 0.2f), 1.5f, 2.6f);
            glm::vec3 dir(std::cos(pitch) * std::cos(yaw), std::sin(pitch), std::cos(pitch) * std::sin(yaw));
            const glm::vec3 next = p + dir;
            if (next.x < 5 || next.x > X - 5 || next.z < 5 || next.z > Z - 5) yaw += glm::pi<float>();  // turn back
            if (next.y < 4 || next.y > Y - 8) pitch = -pitch;
            p += glm::vec3(std::cos(pitch) * std::cos(yaw), std::sin(pitch), std::cos(pitch) * std::sin(yaw));
            p = glm::clamp(p, glm::vec3(4, 3, 4), glm::vec3(X - 4, Y - 7, Z - 4));
        }
    }
    const std::uint8_t timber = add(s, r, kDarkWood), torch = add(s, r, {0.9f, 0.8f, 0.5f}, {5.0f, 3.2f, 1.2f});
    for (int k = 0, corridors = r.irange(2, 3); k < corridors; ++k) {
        // Mine corridor: 4 wide, 4 high, along x then z between two tunnel points of similar height.
        const glm::ivec3 a = glm::ivec3(r.pick(points)), b = glm::ivec3(r.pick(points));
        const int y0 = std::clamp(a.y - 1, 1, Y - 8);
        auto leg = [&](glm::ivec3 from, glm::ivec3 to, bool along_x) {
            const int lo = std::min(along_x ? from.x : from.z, along_x ? to.x : to.z);
            const int hi = std::max(along_x ? from.x : from.z, along_x ? to.x : to.z);
            for (int t = lo; t <= hi; ++t) {
                const glm::ivec3 c = along_x ? glm::ivec3(t, y0, from.z) : glm::ivec3(from.x, y0, t);
                const glm::ivec3 side = along_x ? glm::ivec3(0, 0, 1) : glm::ivec3(1, 0, 0);
                const glm::ivec3 along = along_x ? glm::ivec3(1, 0, 0) : glm::ivec3(0, 0, 1);
                for (int j = -2; j <= 1; ++j)
                    for (int y = 0; y < 4; ++y) {
                        const glm::ivec3 v = c + side * j + glm::ivec3(0, y, 0);
                        if (v.x >= 1 && v.z >= 1 && v.x <= X - 2 && v.z <= Z - 2) s.set(v, 0);
                    }
                if ((t - lo) % 4 == 2) {  // timber frame: two posts and a beam, a torch on one post
                    for (int y = 0; y < 4; ++y) {
                        s.set(c - side * 2 + glm::ivec3(0, y, 0), timber);
                        s.set(c + side + glm::ivec3(0, y, 0), timber);
                    }
                    for (int j = -2; j <= 1; ++j) s.set(c + side * j + glm::ivec3(0, 3, 0), timber);
                    if ((t - lo) % 8 == 2) s.set(c - side * 2 + along + glm::ivec3(0, 2, 0), torch);
                }
            }
        };
        leg(a, {b.x, y0, a.z}, true);
        leg({b.x, y0, a.z}, b, false);
    }
    for (int k = 0, shafts = r.irange(1, 2); k < shafts; ++k) {  // openings to the sky
        const glm::vec3 p = r.pick(points);
        const float rad = r.range(1.2f, 2.0f);
        for (int y = int(p.y); y < Y; ++y)
            for (int z = -2; z <= 2; ++z)
                for (int x = -2; x <= 2; ++x)
                    if (float(x * x + z * z) < rad * rad) s.set(glm::ivec3(int(p.x) + x, y, int(p.z) + z), 0);
    }
    const std::uint8_t crystal = add(s, r, {0.3f, 0.6f, 0.7f}, {1.0f, 2.6f, 3.2f});
    for (int k = 0, n = r.irange(15, 35); k < n; ++k) {  // crystals on tunnel walls: march from a tunnel point
        glm::vec3 p = r.pick(points);
        const glm::vec3 dir = glm::normalize(glm::vec3(r.range(-1, 1), r.range(-1, 1), r.range(-1, 1)) + 1e-3f);
        for (int i = 0; i < 12; ++i, p += dir * 0.5f)
            if (s.solid(glm::ivec3(glm::floor(p)))) {
                if (p.y < Y - 4) s.set(glm::ivec3(glm::floor(p)), crystal);
                break;
            }
    }
    if (r.chance(0.5f)) {  // lava pool on the floor under the lowest tunnel point
        const glm::vec3 low = *std::min_element(points.begin(), points.end(), [](auto& a, auto& b) { return a.y < b.y; });
        const std::uint8_t lava = add(s, r, {0.8f, 0.3f, 0.05f}, {6.0f, 1.6f, 0.25f});
        for (int z = -2; z <= 2; ++z)
            for (int x = -2; x <= 2; ++x) {
                glm::ivec3 v(int(low.x) + x, int(low.y), int(low.z) + z);
                while (v.y > 0 && !s.solid(v)) --v.y;
                if (v.y > 0 && x * x + z * z <= 5) s.set(v, lava);
            }
    }
    set_region(s, {1.5f, 1.5f, 1.5f}, {X - 1.5f, Y - 4.0f, Z - 1.5f});
    s.sun_azimuth = r.range(0.0f, glm::two_pi<float>());
    s.default_time = 12.0f;
    return s;
}

// Sun heading at noon that puts the sun toward `toward` (an azimuth) at `hours` (see lighting_at()).
float azimuth_for(float toward, float hours) {
    const float day_angle = (hours - 6.0f) / 12.0f * glm::pi<float>();
    return toward - (day_angle - 0.5f * glm::pi<float>());
}

// ---- backlit: the only opening is behind the camera, which looks into the room ---------------------------------
VoxelScene backlit(std::uint32_t seed) {
    Rand r(seed, 4);
    const int W = r.irange(8, 12), D = r.irange(10, 14), H = r.irange(4, 5), M = 5;
    VoxelScene s({W + 2 + 2 * M, H + 2, D + 2 + M + 1}, "backlit");
    s.fill({0, 0, 0}, {s.size.x, 1, s.size.z}, add(s, r, r.chance(0.5f) ? kGrass : kPavement));
    const std::vector<glm::vec3> walls = {kPlaster, kWood, kBrick, kStone, kSand};
    const glm::ivec3 lo(M, 0, M), hi(M + W + 2, H + 2, M + D + 2), in_lo = lo + 1, in_hi = hi - 1;
    shell(s, lo, hi, add(s, r, r.pick(walls)), add(s, r, r.chance(0.5f) ? kWood : kStone), add(s, r, kPlaster));
    furnish(s, r, {in_lo.x, in_lo.y, in_lo.z + D / 3}, in_hi, r.irange(2, 5));
    const int ow = r.irange(W / 2, W - 2), oh = r.irange(2, H - 1), oy = r.chance(0.5f) ? 0 : 1;
    wall_rect(s, in_lo, in_hi, 0, r.irange(1, W - ow - 1), oy, ow, std::min(oh, H - oy), 0);  // the -z wall
    set_region(s, glm::vec3(in_lo) + glm::vec3(0.8f, 1.3f, 1.0f), glm::vec3(in_hi.x - 0.8f, in_hi.y - 0.6f, in_lo.z + D * 0.45f));
    s.camera.look = glm::vec3(0.0f, 0.0f, 1.0f);  // away from the opening at -z
    s.default_time = r.range(14.5f, 16.5f);
    // Direction toward the sun has z < 0 at the default time, so sunlight falls in through the opening.
    s.sun_azimuth = azimuth_for(glm::pi<float>() + r.range(-0.5f, 0.5f), s.default_time);
    return s;
}

// ---- bleed: saturated walls and blocks in sunlight from a skylight ---------------------------------------------
VoxelScene bleed(std::uint32_t seed) {
    Rand r(seed, 5);
    const int W = r.irange(9, 13), D = r.irange(9, 13), H = r.irange(5, 7), M = 2;
    VoxelScene s({W + 2 + 2 * M, H + 2, D + 2 + 2 * M}, "bleed");
    s.fill({0, 0, 0}, {s.size.x, 1, s.size.z}, add(s, r, kGrass));
    const glm::ivec3 lo(M, 0, M), hi(M + W + 2, H + 2, M + D + 2), in_lo = lo + 1, in_hi = hi - 1;
    shell(s, lo, hi, add(s, r, kWhite), add(s, r, kWhite), add(s, r, kWhite));
    std::vector<glm::vec3> colours(kWool.begin(), kWool.end() - 1);  // saturated only
    for (int w = 0; w < 4; ++w) {  // each wall a different strong colour
        const std::size_t i = r.g() % colours.size();
        const std::uint8_t m = add(s, r, colours[i]);
        colours.erase(colours.begin() + std::ptrdiff_t(i));
        wall_rect(s, in_lo, in_hi, w, 0, 0, wall_length(in_lo, in_hi, w), H, m);
    }
    for (int k = 0, n = r.irange(3, 6); k < n; ++k) {  // coloured blocks on the floor
        const int a = r.irange(1, 3), b = r.irange(1, 3), c = r.irange(1, 3);
        const glm::ivec3 p(r.irange(in_lo.x, in_hi.x - a), in_lo.y, r.irange(in_lo.z, in_hi.z - c));
        s.fill(p, p + glm::ivec3(a, b, c), add(s, r, r.pick(kWool)));
    }
    const int sw = std::max(3, W / 2), sd = std::max(3, D / 2);  // skylight
    const int sx = r.irange(in_lo.x, in_hi.x - sw), sz = r.irange(in_lo.z, in_hi.z - sd);
    s.fill({sx, in_hi.y, sz}, {sx + sw, in_hi.y + 1, sz + sd}, 0);
    if (r.chance(0.5f)) wall_rect(s, in_lo, in_hi, r.irange(0, 3), 2, 1, 2, 2, 0);
    if (r.chance(0.5f)) {  // a dim coloured glowing block
        const glm::vec3 c = r.pick(kWool);
        s.set({r.irange(in_lo.x, in_hi.x - 1), in_lo.y, r.irange(in_lo.z, in_hi.z - 1)}, add(s, r, c, c * 2.0f));
    }
    ceiling_lamps(s, r, in_lo, in_hi, 1);
    set_region(s, glm::vec3(in_lo) + glm::vec3(0.6f, 1.3f, 0.6f), glm::vec3(in_hi) - glm::vec3(0.6f, 0.7f, 0.6f));
    s.sun_azimuth = r.range(0.0f, glm::two_pi<float>());
    s.default_time = r.range(11.0f, 13.5f);
    return s;
}

// ---- sculpture: one free-standing object, for per-object networks (seed 001's ambient-occlusion MLP) --------------
// A 64^3 grid holding a smooth solid: the union of a torus and 5..8 metaballs (a field sum of r^2 / d^2 above 1),
// minus a few spherical dents, so that it has convex bumps, saddles, concave creases and a hole. No ground, no
// lamps: the object alone, as the seed renders its Bunny or Dragon.
VoxelScene sculpture(std::uint32_t seed) {
    Rand r(seed, 6);
    const int N = 64;
    VoxelScene s({N, N, N}, "sculpture");
    const std::uint8_t m = add(s, r, glm::vec3(0.6f));
    const glm::vec3 c(N * 0.5f);
    std::vector<glm::vec4> balls;  // centre, radius
    for (int k = 0, n = r.irange(5, 8); k < n; ++k)
        balls.emplace_back(c + glm::vec3(r.range(-13, 13), r.range(-13, 13), r.range(-13, 13)), r.range(4.5f, 8.0f));
    std::vector<glm::vec4> dents;
    for (int k = 0, n = r.irange(2, 4); k < n; ++k)
        dents.emplace_back(c + glm::vec3(r.range(-18, 18), r.range(-18, 18), r.range(-18, 18)), r.range(4, 8));
    const float R = r.range(16, 20), tube = r.range(3.0f, 4.5f);  // torus about an axis tilted from +y
    const glm::vec3 axis = glm::normalize(glm::vec3(r.range(-0.6f, 0.6f), 1.0f, r.range(-0.6f, 0.6f)));
    for (int z = 0; z < N; ++z)
        for (int y = 0; y < N; ++y)
            for (int x = 0; x < N; ++x) {
                const glm::vec3 p = glm::vec3(x, y, z) + 0.5f;
                float field = 0;
                for (const auto& b : balls) {
                    const glm::vec3 d = p - glm::vec3(b);
                    field += b.w * b.w / std::max(glm::dot(d, d), 1e-3f);
                }
                const glm::vec3 q = p - c;
                const float h = glm::dot(q, axis);
                const float ring = glm::length(q - h * axis) - R;
                bool solid = field > 1.0f || ring * ring + h * h < tube * tube;
                for (const auto& d : dents) solid = solid && glm::length(p - glm::vec3(d)) > d.w;
                if (solid && x > 0 && y > 0 && z > 0 && x < N - 1 && y < N - 1 && z < N - 1) s.set({x, y, z}, m);
            }
    set_region(s, glm::vec3(0.5f), glm::vec3(N - 0.5f));
    return s;
}

// ---- cornell: seed 004's voxel Cornell boxes (one fixed grid, so per-voxel networks see one coordinate frame) ----
// A closed 40^3 box of 1-block walls: red -x wall, green +x wall, white floor, ceiling and back; 1-2 emissive panels
// in the ceiling (always on) at random places, a fixed skylight the sun falls through at the default time (its patch
// of sunlight on the floor is the "directional light's shadow" of the seed's scenes), and 2-4 boxes of random size,
// place and colour standing on the floor. cornell_pink is the seed's test scene: the same generator plus one more
// object, with the back wall turned pink.
constexpr int kCornellSize = 40;

VoxelScene cornell(std::uint32_t seed, bool pink) {
    Rand r(seed, 7);
    const int N = kCornellSize;
    VoxelScene s({N, N, N}, pink ? "cornell_pink" : "cornell");
    const std::uint8_t white = add(s, r, kWhite);
    s.fill({0, 0, 0}, {N, N, N}, white);
    s.fill({1, 1, 1}, {N - 1, N - 1, N - 1}, 0);
    s.fill({0, 1, 1}, {1, N - 1, N - 1}, add(s, r, glm::vec3(0.63f, 0.07f, 0.05f)));  // red -x wall
    s.fill({N - 1, 1, 1}, {N, N - 1, N - 1}, add(s, r, glm::vec3(0.12f, 0.45f, 0.09f)));  // green +x wall
    // The skylight and the sun are the same in every box (the seed's scenes share their lights' setup; a per-voxel
    // network has no input that could tell it where the sun is): at noon the sun stands 70 degrees high toward
    // -x -z, so its light falls through the opening onto the floor around (20..26, 1, 20..26).
    const int sw = 6, sd = 6, sx = 10, sz = 10;
    s.fill({sx, N - 1, sz}, {sx + sw, N, sz + sd}, 0);
    for (int k = 0, n = r.irange(1, 2); k < n; ++k) {  // emissive ceiling panels, away from the skylight
        const glm::vec3 e = glm::vec3(40.0f, 37.0f, 32.0f) * r.range(0.7f, 1.3f);
        const std::uint8_t m = add(s, r, glm::vec3(0.8f), e);
        const int pw = r.irange(2, 4), pd = r.irange(2, 4);
        for (int tries = 0; tries < 50; ++tries) {
            const int px = r.irange(2, N - 2 - pw), pz = r.irange(2, N - 2 - pd);
            if (px + pw > sx - 1 && px < sx + sw + 1 && pz + pd > sz - 1 && pz < sz + sd + 1) continue;
            s.fill({px, N - 2, pz}, {px + pw, N - 1, pz + pd}, m);
            break;
        }
    }
    for (int k = 0, n = r.irange(2, 4) + (pink ? 1 : 0); k < n; ++k) {  // boxes on the floor
        const int w = r.irange(4, 11), h = r.irange(4, 16), d = r.irange(4, 11);
        const glm::ivec3 lo(r.irange(2, N - 2 - w), 1, r.irange(2, N - 2 - d));
        s.fill(lo, lo + glm::ivec3(w, h, d), add(s, r, r.pick(kWool)));
    }
    // Last, so that cornell_pink:seed=S is cornell:seed=S plus these changes (the random sequence is shared).
    if (pink) s.fill({1, 1, 0}, {N - 1, N - 1, 1}, add(s, r, glm::vec3(0.85f, 0.42f, 0.58f)));  // pink -z wall
    set_region(s, glm::vec3(3.0f, 4.0f, 26.0f), glm::vec3(N - 3.0f, N - 8.0f, N - 3.0f));
    s.camera.look = glm::vec3(0.0f, 0.0f, -1.0f);  // toward the back wall, as the classic view
    s.default_time = 12.0f;
    s.sun_azimuth = 1.25f * glm::pi<float>();
    return s;
}

}  // namespace

const std::vector<std::string>& scene_families() {
    static const std::vector<std::string> f = {"room",    "street",       "cave", "backlit",      "bleed", "sculpture",
                                               "cornell", "cornell_pink", "knot", "superquadric", "blob"};
    return f;
}

VoxelScene generate_scene(const std::string& family, std::uint32_t seed) {
    VoxelScene s;
    if (family == "room") s = room(seed);
    else if (family == "street") s = street(seed);
    else if (family == "cave") s = cave(seed);
    else if (family == "backlit") s = backlit(seed);
    else if (family == "bleed") s = bleed(seed);
    else if (family == "sculpture") s = sculpture(seed);
    else if (family == "cornell") s = cornell(seed, false);
    else if (family == "cornell_pink") s = cornell(seed, true);
    else if (detail::is_mesh_family(family)) s = detail::mesh_family_scene(family, seed, false, family);  // no floor
    else throw InputError("unknown scene family '" + family + "'");
    s.name = family + ":seed=" + std::to_string(seed);
    return s;
}

}  // namespace ngi
