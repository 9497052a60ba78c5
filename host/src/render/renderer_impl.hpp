// The state of a Renderer (ngi/render.hpp) that its methods share across files: the scene on the device, the per-frame
// lighting and camera, the tracer kernels built on first use and the launch budgets. Library-internal. The methods
// live by concept: renderer.cpp (the scene upload, frames: features and reference), ao_geometry.cpp (AO, geometry
// and surface renders), voxel_field.cpp (seed 004's voxel field).
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "ngi/render.hpp"
#include "render/bvh.hpp"
#include "runtime/context.hpp"

namespace ngi {

struct Renderer::Impl {
    static constexpr std::size_t kLocal = 64;  // fixed work-group size (PoCL compiles one work-group function per size)

    // A face of an emissive block that borders air inside the grid (only such faces can be seen or sampled).
    struct EmitterFace {
        glm::ivec3 cell;
        int face;  // 0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z
        std::uint8_t material;
    };

    std::shared_ptr<detail::Context> ctx;
    std::vector<Material> palette;
    std::vector<EmitterFace> emitters;
    glm::ivec3 size;
    detail::Buffer grid, mats, lights, cdf, light, cam, region, portals, portal_range;
    detail::Buffer patches, patch_prob, patch_cdf, patch_range, face_slot, face_index, patch_weight;
    std::unique_ptr<detail::DeviceBvh> bvh;  // the triangle mesh (placeholder buffers when there is none)
    bool has_mesh = false, has_blocks = false;
    int bvh_depth = 0;
    bool have_regions = false, have_portals = false;
    int npatches = 0;
    std::vector<std::int32_t> patch_static_range;  // per region: first, count
    bool patches_lit = false;                        // any region has sunlit patches this frame
    std::vector<float> patch_light_key;              // light parameters the patch weights were computed for
    // pt_patch_weights of each program that lights the scene (pathtrace, voxel_field: both list patch_weights.cl),
    // so a frame runs it from the program it is rendered with and never builds another one for it.
    std::map<std::string, detail::Kernel> k_patch;
    detail::Buffer features, feature_rays, mean, var, ref_rays;
    int buffers_n = 0;
    int nlights = 0;
    float inv_total = 0.0f;
    bool area_on = false;  // this frame has an area light (one more shadow ray per path vertex)
    detail::Kernel k_features, k_reference, k_ao, k_geometry, k_surface;
    detail::Buffer ao;  // render_ao's output
    detail::Buffer geometry;  // render_geometry's and render_surface's output
    // Seed 004's voxel field (render_voxel_field, voxel_visibility): kernels made on first use.
    detail::Kernel k_vf_sun, k_vf_sh, k_vf_probe, k_vf_face, k_vf_vis;

    // Refuses settings out of range (face size, samples, bounces): InputError.
    static void check_settings(const RenderSettings& s);

    // The kernel `name` of the tracer program `program` in slot k, built at its first use: each render call compiles
    // only the program it runs (an AO-only renderer never builds the path tracer's lighting).
    detail::Kernel& kernel(detail::Kernel& k, const char* program, const char* name);
    // Work-group size of a tracer launch: kLocal, or less where the driver allows fewer work-items for these
    // register-heavy kernels (Mesa 22.3 rusticl on llvmpipe reports a CL_KERNEL_WORK_GROUP_SIZE of 32 and a
    // conforming driver rejects a larger local size). Results do not depend on it.
    static std::size_t local_size(const detail::Kernel& k) {
        const std::size_t wg = k.max_work_group();
        return wg > 0 ? std::min(kLocal, wg) : kLocal;
    }

    // Per frame: lamp level into the material table, the emitter list and its CDF, sun/sky, camera.
    // `lit_program`: the program of the frame's kernels when they light the scene (the sunlit-patch weights are
    // updated only for those, by its pt_patch_weights), else nullptr.
    void upload_frame(const CameraPose& pose, const Lighting& l, const RenderSettings& rs, const char* lit_program);

    // Samples per pixel one launch may take. Unlimited (INT_MAX) unless the driver ends loops after a fixed number
    // of iterations per work-item (Context::loop_limit; llvmpipe: 65,535, counted over every loop of the kernel).
    // Bound per sample: per bounce up to six DDA walks (primary or continuation, sun, emitter, portal, patch and
    // its sun ray; a seventh with an area light) of at most dims.x + dims.y + dims.z + 3 steps, plus three binary
    // searches of at most 32 steps. Call after upload_frame (area_on).
    int samples_per_launch(int max_bounces, const char* what) const;

    // Renders the six faces' features into `out` (layout: pathtrace.cl's F_CHANNELS planes per face).
    void enqueue_features(const CameraPose& pose, const Lighting& lighting, const RenderSettings& s, cl_mem out);

    void ensure_buffers(int n);

    template <class... A>
    void set_scene_args(detail::Kernel& k, const RenderSettings& rs, const A&... rest) {
        k.args(grid, size.x, size.y, size.z, mats, lights, cdf, nlights, inv_total, light, region, portals,
               portal_range, int(have_regions), int(rs.sky_portals && have_portals), patches, patch_prob, patch_cdf,
               patch_range, face_slot, face_index, int(rs.sunlit_patches && patches_lit), bvh->nodes(),
               bvh->triangles(), bvh->triangle_info(), bvh->vertex_normals(), int(has_mesh), int(has_blocks), rest...);
    }

    // Per-frame patch probabilities (only when the sun or the materials changed): weights on the device, then
    // normalized per region on the host.
    void update_patches(const float* L, const std::vector<float>& m, const RenderSettings& rs, const char* program);

    // The SH projection (kernels/voxel_field.cl vf_sh, with the sun's visibility first unless indirect_only) at V
    // uploaded probe points and cells, after upload_frame: the [V][27] buffer; the rays traced are added to
    // rays_total (`rays`: a [V] uint scratch buffer). Shared by render_voxel_field and project_points_sh.
    detail::Buffer project_sh(const detail::Buffer& probe, const detail::Buffer& cells, std::size_t V,
                              const Lighting& lighting, const VoxelFieldSettings& s, bool indirect_only,
                              const detail::Buffer& rays, std::uint64_t& rays_total);

    // Samples one launch of a kernel may take when each work-item loops `fixed` times plus `per_sample` times per
    // sample (llvmpipe's loop limit, as samples_per_launch), at most `cap` when cap > 0.
    int items_per_launch(long fixed, long per_sample, int cap, const char* what) const;
    // Loop iterations of one trace(): the DDA walk at most, plus the BVH's node visits and triangle tests. The
    // latter have no useful bound (a ray may visit every node); 32 per level of the tree is an estimate well
    // above what rays measure (bvh_trace_rays reports the steps; tests/test_bvh.cpp), so a launch's loop budget
    // on llvmpipe holds in practice, not by proof (docs/RELIABILITY.md).
    long trace_loops() const {
        return (has_blocks ? long(size.x) + size.y + size.z + 3 : 1) + (has_mesh ? 32L * bvh_depth : 0);
    }
    long bounce_loops() const { return 6 * trace_loops() + 3 * 32; }  // as samples_per_launch

    std::uint64_t sum_rays(const detail::Buffer& b, std::size_t count);
};

}  // namespace ngi
