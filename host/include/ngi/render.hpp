// The OpenCL voxel path tracer: lighting (sun, sky, lamps; time of day), feature buffers for the six faces of the
// camera cluster and the path-traced reference lighting of one face. docs/RENDERER.md defines every quantity.
//
// Light normalization: every lighting buffer ("direct", the reference) holds irradiance / pi, i.e. the radiance a
// white Lambertian surface would reflect, so that reflected radiance = albedo * lighting. Emission and sky values
// are radiance in the same unit. A frame composes as  final = albedo * (reference) + emission + env.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "ngi/area_light.hpp"
#include "ngi/device.hpp"
#include "ngi/device_buffer.hpp"
#include "ngi/image.hpp"
#include "ngi/scene.hpp"

namespace ngi {

// Seed 004's voxel radiance field (defined in ngi/voxel_field.hpp; include that to call the methods below).
struct SurfaceVoxels;
struct VoxelFieldSettings;
struct VoxelField;
struct PointSh;

// A distant sun: a disc of uniform radiance subtending `angular_radius` around `direction`.
struct Sun {
    glm::vec3 direction{0, 1, 0};  // unit, from the scene toward the sun
    glm::vec3 irradiance{0.0f};    // on a surface facing the sun, unoccluded (so direct = irradiance * cos / pi)
    float angular_radius = 0.0f;   // radians; 0 = hard shadows
};

// Analytic sky radiance (the sun disc is not part of it: the sun is a separate light, as in Blender):
//   up (d.y >= 0):  horizon + (zenith - horizon) * d.y^0.5  +  glow * ((1 + d.sun) / 2)^8
//   down (d.y < 0): ground  (light from the world below the horizon, outside the grid)
struct Sky {
    glm::vec3 zenith{0.0f}, horizon{0.0f}, ground{0.0f}, glow{0.0f};
};

struct Lighting {
    Sun sun;
    Sky sky;
    float lamp_level = 0.0f;  // multiplies the emission of lamp materials (0 = off by day, 1 = on at night)
    // A rectangular emitter that is not a block (ngi/area_light.hpp); off by default (radiance 0), and then the
    // renderer's output is bit for bit what it was without it. lighting_at() leaves it off.
    AreaLight area_light;
};

// Time of day in hours (0..24; 6 = sunrise, 12 = noon, 18 = sunset, night after ~18.7): the sun's path (heading
// `sun_azimuth` at noon, 70 degrees high), its reddening and fading near the horizon, the sky's colours from
// blue day through orange twilight to dark night, and the lamps coming on as the sun sets.
Lighting lighting_at(float hours, float sun_azimuth);

// The sky model above, evaluated on the host (the kernel has the same formula; tests compare them).
glm::vec3 sky_radiance(const Sky& sky, const Sun& sun, glm::vec3 unit_dir);

// Position of the cluster centre (world metres) and the front camera's look and up (camera.hpp conventions).
struct CameraPose {
    glm::vec3 position{0.0f};
    glm::vec3 look{0, 0, -1}, up{0, 1, 0};
};

// Samples per pixel of the direct-light feature that make it an engine's input: converged, as a shadow-mapped sun and
// a prefiltered sky are noise-free (issue 45: with 8 spp the networks' apparent gain was smoothing the tracer's own
// noise). The default of RenderSettings, `ngi render`, ngi.Renderer.render and the planner.
constexpr int kEngineFeatureSpp = 1024;

struct RenderSettings {
    int n = 128;               // face size in pixels
    int feature_spp = kEngineFeatureSpp;  // samples per pixel of the "direct" feature (the other features are exact)
    int reference_spp = 64;    // samples per pixel of the reference lighting
    int max_bounces = 8;       // indirect bounces of the reference (0 = direct light only); Russian roulette
    int rr_start = 2;          // bounces before Russian roulette starts
    bool reference = true;     // also render the reference of `reference_face`
    Face reference_face = Face::Front;
    std::uint32_t seed = 0;    // per-frame seed of the counter-based RNG: same seed, same image
    bool sky_portals = true;   // also sample the sky through the openings of rooms (same expectation, less noise)
    bool sunlit_patches = true;  // also sample sunlight reflected off sunlit faces in rooms (same, less noise)
};

struct RenderStats {
    double feature_ms = 0, reference_ms = 0;  // device time incl. read-back
    std::uint64_t feature_rays = 0, reference_rays = 0;  // rays traced (primary, shadow and bounce rays)
    double reference_rel_stderr = 0;          // mean over lit pixels of stderr/mean of the reference (luminance)
};

// A scene uploaded to one device. Rendering is deterministic: same scene, pose, lighting and settings (seed),
// same result, whatever the device's work-group scheduling.
class Renderer {
public:
    Renderer(const Device& device, const VoxelScene& scene);
    ~Renderer();
    Renderer(Renderer&&) noexcept;
    Renderer& operator=(Renderer&&) noexcept;

    // All six faces' features (albedo, normal, depth, direct, emission, env) and, if settings.reference, the
    // reference lighting of settings.reference_face in Frame::reference. Frame::look/up come from the pose.
    Frame render(const CameraPose& pose, const Lighting& lighting, const RenderSettings& settings,
                 RenderStats* stats = nullptr);

    // The six faces' features rendered straight into `planes` (on this renderer's device, at least
    // frame_planes_bytes(n, 6) bytes): the frame-plane layout of ngi/pipeline.hpp with emission and env present,
    // so SurroundPipeline::enqueue takes them as FrameDesc{6, true, true, pose.look, pose.up}. The frame's data
    // never leaves the device (only the per-frame parameters are uploaded: materials, emitters, camera), the same
    // values as render()'s faces, bit for bit. Asynchronous unless `stats` is given (it reads the ray counts).
    void render_planes(const CameraPose& pose, const Lighting& lighting, const RenderSettings& settings,
                       const DeviceBuffer& planes, RenderStats* stats = nullptr);

    // Ambient occlusion of one face (seed 001), 1 x N x N: per pixel the fraction of `rays` cosine-weighted hemisphere
    // rays from the visible surface that travel `max_distance` metres (> 0; infinity allowed) without meeting a block:
    // 1 = unoccluded; 1 where the pixel sees no surface. Deterministic in settings.seed. settings.n is the size;
    // the lighting and the other settings are not used.
    Image render_ao(const CameraPose& pose, const RenderSettings& settings, int rays, float max_distance,
                    Face face = Face::Front);

    // Object-space geometry of one face for per-pixel networks (seed 001), 7 x N x N: the smooth normal (3), the
    // voxel face normal (3) and the planar depth in metres (1) of the visible surface; zero normals and depth 1e4
    // where the pixel sees no surface. Scenes are not transformed, so object space is world space (+y up).
    // Smooth normal = minus the gradient of the block occupancy blurred by a Gaussian of `smooth_sigma` blocks
    // (0..kMaxSmoothSigma; 0 = the face normal), the face normal where that gradient vanishes or points into the
    // face. Voxel face normals take only six values; the smooth ones vary across a face near edges and corners.
    static constexpr float kMaxSmoothSigma = 4.0f;
    Image render_geometry(const CameraPose& pose, const RenderSettings& settings, float smooth_sigma,
                          Face face = Face::Front);

    // What each pixel of one face sees of the scene's triangle mesh, 6 x N x N: the three vertex indices of the
    // triangle (TriangleMesh::triangles order; -1 where the pixel sees a block or nothing) and the barycentric
    // weights of those vertices at the visible point (0 there). For baking values per vertex from rendered views.
    Image render_surface(const CameraPose& pose, const RenderSettings& settings, Face face = Face::Front);

    // The reference lighting of one face (3 x N x N) and, if `variance` is given, the per-pixel variance of that
    // estimate (the sample variance / spp, per channel), for error bars.
    Image render_reference(const CameraPose& pose, const Lighting& lighting, const RenderSettings& settings,
                           Image* variance = nullptr, RenderStats* stats = nullptr);

    // Seed 004's ground truth for the surface voxels of this renderer's scene (surface_voxels() of the same scene):
    // per voxel the SH projection (bands 0-2, RGB) of the incident radiance at its probe point, the direct and full
    // lighting there and the full lighting of each exposed face (docs/VOXEL_FIELD.md). Deterministic in
    // settings.seed. Throws InputError for voxels of another grid size and for settings out of range.
    VoxelField render_voxel_field(const SurfaceVoxels& voxels, const Lighting& lighting,
                                  const VoxelFieldSettings& settings);

    // The same SH projection at arbitrary points of the scene's grid box (an irradiance-probe grid's bake, docs/ADAPT.md
    // "probe grid"), settings.directions directions per point (point_samples unused). indirect_only: only light that
    // has bounced at least once (no sky, no emission seen directly, no sun), what a bake adds to an engine's direct
    // light. A point inside a solid block sees its own block as black. Throws InputError for no points, more than
    // kMaxFieldVoxels, a point that is not finite or outside [0, size], settings out of range, an area light.
    PointSh project_points_sh(const std::vector<glm::vec3>& points, const Lighting& lighting,
                              const VoxelFieldSettings& settings, bool indirect_only);

    // Visibility between the voxels' probe points: uint32 words [V][ceil(V / 32)], bit j % 32 of word j / 32 of row i
    // set when the segment from probe i to probe j crosses no solid block other than voxels i and j themselves.
    // Symmetric, diagonal 0. Throws InputError beyond kMaxVisibilityVoxels voxels.
    std::vector<std::uint32_t> voxel_visibility(const SurfaceVoxels& voxels);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ngi
