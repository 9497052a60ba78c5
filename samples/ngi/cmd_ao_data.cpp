// ngi ao-data: the data of seed 001's ambient-occlusion MLP for one object: views on an orbit around its bounding
// sphere, each an "AO frame folder" (docs/RESULTS_AO.md): normal.npy (smooth object-space normals, [3, N, N]),
// face_normal.npy ([3, N, N]), depth.npy ([1, N, N], planar depth, 1e4 = no surface) and ao.npy ([1, N, N], the
// ray-traced reference, 1 = unoccluded); for scenes with triangles also surface.npy ([6, N, N]: the visible
// triangle's vertex indices, -1 where none, and barycentric weights; Renderer::render_surface). Two orbits: "orbit"
// (the seed's rotating camera, training data) and
// "heldout" (other azimuths and heights, for evaluation). Resumable: finished views are kept, a view is written
// all-or-nothing; progress with an ETA on stderr.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include <glm/glm.hpp>
#include <glm/gtc/constants.hpp>

#include "commands.hpp"
#include "ngi/error.hpp"
#include "ngi/output_folder.hpp"
#include "ngi/render.hpp"
#include "ngi/scene.hpp"
#include "ngi/tensor.hpp"

namespace ngi_cli {
namespace {

struct Sphere {
    glm::vec3 centre{0.0f};
    float radius = 0.0f;
};

// Bounding sphere of the object: the solid blocks and the triangle mesh's vertices (a mesh scene's grid is only
// air around its mesh). Centre: the centre of their joint bounding box; radius: the farthest block corner or vertex.
Sphere bounding_sphere(const ngi::VoxelScene& s) {
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (int z = 0; z < s.size.z; ++z)
        for (int y = 0; y < s.size.y; ++y)
            for (int x = 0; x < s.size.x; ++x)
                if (s.solid({x, y, z})) {
                    lo = glm::min(lo, glm::vec3(x, y, z));
                    hi = glm::max(hi, glm::vec3(x + 1, y + 1, z + 1));
                }
    if (!s.mesh.empty()) {
        const auto [mlo, mhi] = ngi::mesh_bounds(s.mesh);
        lo = glm::min(lo, mlo);
        hi = glm::max(hi, mhi);
    }
    if (!(lo.x <= hi.x)) throw ngi::InputError("ngi ao-data: scene " + s.name + " has no solid block and no triangle");
    Sphere b;
    b.centre = (lo + hi) * 0.5f;
    for (int z = 0; z < s.size.z; ++z)
        for (int y = 0; y < s.size.y; ++y)
            for (int x = 0; x < s.size.x; ++x)
                if (s.solid({x, y, z}))
                    for (int c = 0; c < 8; ++c) {
                        const glm::vec3 p(x + (c & 1), y + (c >> 1 & 1), z + (c >> 2 & 1));
                        b.radius = std::max(b.radius, glm::length(p - b.centre));
                    }
    for (const glm::uvec3& t : s.mesh.triangles)
        for (int k = 0; k < 3; ++k) b.radius = std::max(b.radius, glm::length(s.mesh.positions[t[k]] - b.centre));
    return b;
}

// View k of an orbit around the sphere at 1.15 x the distance at which it fills the 90-degree face.
// "orbit": azimuth 2 pi k / count, elevation 35 deg sin(3 x azimuth) (three up-and-down swings per turn);
// "heldout": azimuths half a step (of its own count) off, elevation 50 deg sin(2 x azimuth + 1).
ngi::CameraPose orbit_pose(const Sphere& b, bool heldout, int k, int count) {
    const float two_pi = glm::two_pi<float>();
    const float az = heldout ? two_pi * (float(k) + 0.5f) / float(count) + 0.1f : two_pi * float(k) / float(count);
    const float el = heldout ? glm::radians(50.0f) * std::sin(2.0f * az + 1.0f) : glm::radians(35.0f) * std::sin(3.0f * az);
    const float dist = 1.15f * b.radius / std::sin(glm::quarter_pi<float>());
    const glm::vec3 dir(std::cos(el) * std::cos(az), std::sin(el), std::cos(el) * std::sin(az));
    ngi::CameraPose p;
    p.position = b.centre + dist * dir;
    p.look = -dir;
    p.up = glm::vec3(0, 1, 0);
    return p;
}

std::string hms(double s) {
    const long t = long(s + 0.5);
    char b[32];
    std::snprintf(b, sizeof b, "%ld:%02ld:%02ld", t / 3600, t / 60 % 60, t % 60);
    return b;
}

ngi::Tensor planes(const ngi::Image& img, int first, int count) {
    ngi::Tensor t({count, img.height, img.width});
    const std::size_t plane = std::size_t(img.width) * img.height;
    std::copy(img.data.begin() + std::ptrdiff_t(first * plane), img.data.begin() + std::ptrdiff_t((first + count) * plane),
              t.data.begin());
    return t;
}

// ao-data resumes into its own folder, so it cannot stage the whole folder as the other commands do; it refuses,
// as they do, a folder holding anything it does not write (it used to add its views to any folder, e.g. a frame
// folder or a home directory). Its own: ao_data.json, orbit/ and heldout/ holding vNNNN view folders (and the
// vNNNN.tmp-* staging folders a killed run leaves behind).
void check_ao_data_folder(const std::string& out) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::is_directory(out, ec)) return;  // absent: created later
    auto refuse = [&](const fs::path& p) {
        throw ngi::InputError("write " + out + ": holds '" + p.lexically_relative(out).string() +
                              "', which ngi ao-data does not write; refusing to write into it (remove it or choose "
                              "another --out)");
    };
    auto is_view = [](const std::string& name) {
        const std::string stem = name.substr(0, name.find(".tmp-"));
        return stem.size() >= 5 && stem[0] == 'v' && stem.find_first_not_of("0123456789", 1) == std::string::npos;
    };
    for (fs::directory_iterator it(out, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string name = it->path().filename().string();
        if (name == "ao_data.json" && it->is_regular_file(ec)) continue;
        if ((name == "orbit" || name == "heldout") && it->is_directory(ec)) {
            for (fs::directory_iterator v(it->path(), ec), vend; !ec && v != vend; v.increment(ec))
                if (!is_view(v->path().filename().string()) || !v->is_directory(ec)) refuse(v->path());
            if (ec) break;
            continue;
        }
        refuse(it->path());
    }
    if (ec) throw ngi::InputError("write " + out + ": cannot be listed: " + ec.message());
}

struct Options {
    std::string spec, out, device;
    int views = 128, heldout = 32, n = 256, rays = 256;
    double max_distance = 4.0, sigma = 1.5;
};

int run(const Options& o) {
    const std::string &spec = o.spec, &out = o.out;
    const int views = o.views, heldout = o.heldout, rays = o.rays;
    ngi::RenderSettings rs;
    rs.n = o.n;
    const float max_distance = float(o.max_distance), sigma = float(o.sigma);
    std::error_code ec;
    if (std::filesystem::exists(out, ec) && !std::filesystem::is_directory(out, ec))
        throw ngi::InputError("ngi ao-data: " + out + " exists and is not a folder");
    check_ao_data_folder(out);  // before the device and the scene: a mistyped --out costs nothing
    ngi::Device device = ngi::Device::open(o.device);
    const ngi::VoxelScene scene = ngi::make_scene(spec);
    const Sphere b = bounding_sphere(scene);
    ngi::Renderer renderer(device, scene);
    std::filesystem::create_directories(out, ec);
    if (ec) throw ngi::InputError("ngi ao-data: cannot create " + out + ": " + ec.message());
    char meta[1024];
    std::snprintf(meta, sizeof meta,
                  "{\n  \"scene\": \"%s\",\n  \"n\": %d,\n  \"rays\": %d,\n  \"max_distance\": %.9g,\n  \"sigma\": %.9g,\n"
                  "  \"views\": %d,\n  \"heldout_views\": %d,\n  \"sphere_centre\": [%.9g, %.9g, %.9g],\n"
                  "  \"sphere_radius\": %.9g\n}\n",
                  scene.name.c_str(), rs.n, rays, double(max_distance), double(sigma), views, heldout,
                  double(b.centre.x), double(b.centre.y), double(b.centre.z), double(b.radius));
    {  // rewritten on every run (it holds only the parameters); checked like every other write
        const std::string meta_path = out + "/ao_data.json";
        std::FILE* f = std::fopen(meta_path.c_str(), "wb");
        const bool ok = f && std::fputs(meta, f) >= 0;
        if (!f || std::fclose(f) != 0 || !ok) throw ngi::InputError("write " + meta_path + ": failed");
    }

    const int total = views + heldout;
    int done = 0, rendered = 0;
    double seconds = 0;
    const bool tty = isatty(STDERR_FILENO);
    for (int split = 0; split < 2; ++split) {
        const int count = split ? heldout : views;
        for (int k = 0; k < count; ++k, ++done) {
            char name[64];
            std::snprintf(name, sizeof name, "%s/v%04d", split ? "heldout" : "orbit", k);
            const std::string dir = out + "/" + name;
            if (std::filesystem::exists(dir + "/ao.npy", ec)) continue;  // finished earlier (folders land whole)
            const auto t0 = std::chrono::steady_clock::now();
            const ngi::CameraPose pose = orbit_pose(b, split == 1, k, count);
            rs.seed = std::uint32_t(split * 100000 + k + 1);
            const ngi::Image g = renderer.render_geometry(pose, rs, sigma);
            const ngi::Image ao = renderer.render_ao(pose, rs, rays, max_distance);
            // Mesh scenes also get surface.npy: the triangle's vertex indices and barycentric weights per pixel,
            // from which an evaluation bakes AO per vertex (the mesh analogue of the per-face bake).
            std::vector<std::string> files{"normal.npy", "face_normal.npy", "depth.npy", "ao.npy", "view.json"};
            if (!scene.mesh.empty()) files.push_back("surface.npy");
            ngi::OutputFolder f(dir, "write", files);
            if (!scene.mesh.empty()) {
                const ngi::Image sf = renderer.render_surface(pose, rs);
                f.write("surface.npy", [&](const std::string& p) { ngi::write_npy(p, planes(sf, 0, 6)); });
            }
            f.write("normal.npy", [&](const std::string& p) { ngi::write_npy(p, planes(g, 0, 3)); });
            f.write("face_normal.npy", [&](const std::string& p) { ngi::write_npy(p, planes(g, 3, 3)); });
            f.write("depth.npy", [&](const std::string& p) { ngi::write_npy(p, planes(g, 6, 1)); });
            f.write("ao.npy", [&](const std::string& p) { ngi::write_npy(p, planes(ao, 0, 1)); });
            char view[512];
            std::snprintf(view, sizeof view,
                          "{\"position\": [%.9g, %.9g, %.9g], \"look\": [%.9g, %.9g, %.9g], \"up\": [0, 1, 0], "
                          "\"seed\": %u}\n",
                          double(pose.position.x), double(pose.position.y), double(pose.position.z),
                          double(pose.look.x), double(pose.look.y), double(pose.look.z), rs.seed);
            f.write_text("view.json", view);
            f.commit();
            seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            ++rendered;
            const double per = seconds / rendered;
            std::fprintf(stderr, "%sao-data %s: %d/%d views  %.2f s/view  ETA %s%s", tty ? "\r" : "", scene.name.c_str(),
                         done + 1, total, per, hms(per * (total - done - 1)).c_str(), tty ? "\x1b[K" : "\n");
        }
    }
    if (tty) std::fputc('\n', stderr);
    std::printf("%d views (%d rendered now) of %s, N = %d, %d rays, max distance %g -> %s\n", total, rendered,
                scene.name.c_str(), rs.n, rays, double(max_distance), out.c_str());
    return 0;
}

}  // namespace

Run add_ao_data(CLI::App& app) {
    auto o = std::make_shared<Options>();
    CLI::App* cmd = add_command(
        app, "ao-data", "seed 001's AO data: orbit views of one object",
        "Per view: smooth normals, face normals, depth and the ray-traced AO (normal.npy, face_normal.npy, depth.npy, "
        "ao.npy, view.json) in DIR/orbit/vNNNN (training) and DIR/heldout/vNNNN (evaluation). Resumable: finished "
        "views are kept. Progress with an ETA on stderr.");
    add_path(*cmd, "--scene", o->spec, "SPEC",
             "a procedural family[:seed=S] (sculpture, knot, superquadric, blob, ...), or a .vox or mesh file", true);
    add_path(*cmd, "--out", o->out, "DIR", "the data folder", true);
    add_integer(*cmd, "--views", o->views, 0, 100000, "V", "views on the training orbit");
    add_integer(*cmd, "--heldout-views", o->heldout, 0, 100000, "V", "views on the held-out orbit");
    add_integer(*cmd, "--n", o->n, 16, 4096, "N", "image size in pixels (N x N)");
    add_integer(*cmd, "--rays", o->rays, 1, 1 << 20, "R", "AO rays per pixel");
    add_real(*cmd, "--max-distance", o->max_distance, 1e-3, 1e6, "DIST", "AO ray length");
    add_real(*cmd, "--sigma", o->sigma, 0.0, double(ngi::Renderer::kMaxSmoothSigma), "S",
             "Gaussian smoothing of the normals, in blocks (0: the face normals)");
    add_device(*cmd, o->device);
    return [o] { return run(*o); };
}

}  // namespace ngi_cli
