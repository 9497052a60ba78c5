// ngi ao: an AO frame folder (normal.npy or face_normal.npy, as the model says; `ngi ao-data` writes them) + a
// trained AO model -> ao.npy and ao.png, and, when the folder holds the ray-traced reference (ao.npy),
// compare.png (network | reference | |difference|) and metrics.json over the object's pixels.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "ngi/ao.hpp"
#include "ngi/error.hpp"
#include "ngi/image_io.hpp"
#include "ngi/metrics.hpp"
#include "ngi/model.hpp"
#include "ngi/output_folder.hpp"
#include "ngi/tensor.hpp"
#include "side_by_side.hpp"

namespace ngi_cli {
namespace {

ngi::Image image_from_npy(const std::string& path, int channels) {
    ngi::Tensor t = ngi::read_npy(path);  // checks the file and its values against the host-memory limit
    std::vector<int> s = t.shape;
    if (s.size() == 4 && s[0] == 1) s.erase(s.begin());
    if (s.size() != 3 || s[0] != channels || s[1] < 1 || s[2] < 1)
        throw ngi::InputError(path + ": shape " + ngi::shape_string(t.shape) + ", expected [" + std::to_string(channels) +
                              ", H, W]");
    ngi::Image img;  // the tensor's values are moved, not copied: one copy of a large frame, not two
    img.width = s[2];
    img.height = s[1];
    img.channels = channels;
    img.data = std::move(t.data);
    return img;
}

ngi::Tensor tensor_from_image(const ngi::Image& img) {
    ngi::Tensor t;
    t.shape = {img.channels, img.height, img.width};
    t.data = img.data;
    return t;
}

struct Options {
    std::string frame, model_path, out_dir, device;
    double radius = -1.0;  // < 0: the model's radius scaled to the image
};

int run(const Options& o) {
    const std::string model_path = ngi::resolve_model(o.model_path);  // a file, or a shipped model's name
    const std::string &frame = o.frame, &out_dir = o.out_dir;
    const double radius = o.radius;
    ngi::OutputFolder out(out_dir, "write", {"ao.npy", "ao.png", "compare.png", "metrics.json"});
    ngi::Device device = ngi::Device::open(o.device);
    ngi::AoNetwork net = ngi::AoNetwork::load(device, model_path);
    // The kind of normals the model was trained on (docs/CONVENTIONS.md section 15).
    const std::string normals_file = net.normals() == "face" ? "face_normal.npy" : "normal.npy";
    const ngi::Image normals = image_from_npy(frame + "/" + normals_file, 3);
    const std::string ref_path = frame + "/ao.npy";
    std::error_code ec;
    const bool has_ref = std::filesystem::exists(ref_path, ec);
    ngi::Image ref;
    if (has_ref) {
        ref = image_from_npy(ref_path, 1);
        if (ref.width != normals.width || ref.height != normals.height)
            throw ngi::InputError(ref_path + " is " + std::to_string(ref.width) + "x" + std::to_string(ref.height) +
                                  " but " + normals_file + " is " + std::to_string(normals.width) + "x" +
                                  std::to_string(normals.height));
    }
    const float r = radius < 0 ? net.radius_for(normals.height) : float(radius);
    ngi::RunInfo info;
    const auto t0 = std::chrono::steady_clock::now();
    const ngi::Image ao = net.run(normals, r, &info);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    out.write("ao.npy", [&](const std::string& p) { ngi::write_npy(p, tensor_from_image(ao)); });
    out.write("ao.png", [&](const std::string& p) { ngi::write_png(p, ao, ngi::PngEncoding::Srgb); });
    std::printf("ao         %s, %dx%d, ring radius %.3g px, %.1f ms (first call: includes building the programs)\n", model_path.c_str(),
                normals.width, normals.height, double(r), ms);
    if (info.sanitized_inputs) std::printf("sanitized  %d non-finite normal components\n", info.sanitized_inputs);
    if (has_ref) {
        // Metrics over the object's pixels (background: no surface in the normals). SSIM needs whole windows: it
        // is taken over the image with the background equal (1) in both, and reported as such.
        double se = 0;
        std::size_t fg = 0;
        ngi::Image diff(ao.width, ao.height, 1), masked_ref = ref;
        for (std::size_t i = 0; i < ao.plane(); ++i) {
            const bool surface = normals.data[i] != 0 || normals.data[i + ao.plane()] != 0 ||
                                 normals.data[i + 2 * ao.plane()] != 0;
            if (!surface) masked_ref.data[i] = 1.0f;
            const double d = double(ao.data[i]) - masked_ref.data[i];
            diff.data[i] = float(std::abs(d));
            if (surface) {
                se += d * d;
                ++fg;
            }
        }
        const double mse = fg ? se / double(fg) : 0.0;
        const ngi::ImageMetrics whole = ngi::compare_images(device, ao, masked_ref, 1.0);
        nlohmann::json m = {
            {"model", model_path},
            {"radius_px", r},
            {"object_pixels", fg},
            {"mse_object", mse},
            {"psnr_object", fg && mse > 0 ? nlohmann::json(10.0 * std::log10(1.0 / mse)) : nlohmann::json(nullptr)},
            {"whole_image", nlohmann::json::parse(ngi::to_json(whole))},
            {"whole_image_note", "background set to 1 in the reference as in the network output; masked SSIM: "
                                 "python3 -m ngi_train.ao.evaluate"}
        };
        out.write_text("metrics.json", m.dump(2) + "\n");
        out.write("compare.png", [&](const std::string& p) {
            ngi::write_png(p, hconcat({&ao, &masked_ref, &diff}), ngi::PngEncoding::Srgb);
        });
        std::printf("metrics    object pixels %zu, MSE %.5f, whole-image SSIM %.4f\n", fg, mse, whole.ssim);
    }
    out.commit();
    std::printf("written    %s\n", out_dir.c_str());
    return 0;
}

}  // namespace

Run add_ao(CLI::App& app) {
    auto o = std::make_shared<Options>();
    CLI::App* cmd = add_command(
        app, "ao", "AO of an AO frame folder (ngi ao-data) with a trained AO MLP",
        "Writes ao.npy and ao.png and, when the folder holds the reference, compare.png (network | reference | "
        "|difference|) and metrics.json over the object's pixels.");
    add_path(*cmd, "--frame", o->frame, "DIR", "the AO frame folder (normal.npy or face_normal.npy)", true);
    add_path(*cmd, "--model", o->model_path, "M",
             "the trained AO model: a .safetensors file or a shipped model's name (ao_bunny_32x16)", true);
    add_path(*cmd, "--out", o->out_dir, "DIR", "the folder to write", true);
    add_real(*cmd, "--radius", o->radius, -1.0, 65536.0, "PX",
             "ring radius in pixels; 0: the seed's inference, negative: the model's radius scaled to the image",
             "the model's");
    add_device(*cmd, o->device);
    return [o] { return run(*o); };
}

}  // namespace ngi_cli
