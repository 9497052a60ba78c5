// Image files (EXR, PNG, .npy by extension) and the image metrics (MSE, PSNR, SSIM as scikit-image computes them).
#include <cmath>

#include "common.hpp"
#include "ngi/image_io.hpp"
#include "ngi/metrics.hpp"

namespace ngi_py {

namespace {
ngi::PngEncoding png_encoding(bool srgb) { return srgb ? ngi::PngEncoding::Srgb : ngi::PngEncoding::Linear; }

py::object number_or_none(double v) { return std::isnan(v) ? py::none() : py::object(py::float_(v)); }
}  // namespace

void register_io(py::module_& m) {
    m.def("read_image", [](const py::object& path) {
        const std::string p = path_string(path, "read_image: path");
        ngi::Image img = [&] {
            py::gil_scoped_release release;
            return ngi::read_image(p);
        }();
        return from_image(std::move(img));
    }, py::arg("path"), ".exr, .png (linear: value / (2^bits - 1)) or .npy, by extension -> float32 [C, H, W].");
    m.def("write_image", [](const py::object& path, const py::object& image) {
        const std::string p = path_string(path, "write_image: path");
        ngi::Image img = to_image(image, "write_image: image");
        py::gil_scoped_release release;
        ngi::write_image(p, img);
    }, py::arg("path"), py::arg("image"),
       "[C, H, W] or [H, W] float -> .exr (float samples), .png (8-bit, linear, clamped to [0, 1]) or .npy, by "
       "extension; written to a temporary file renamed into place.");
    m.def("read_exr", [](const py::object& path) {
        const std::string p = path_string(path, "read_exr: path");
        std::vector<std::string> names;
        ngi::Image img = [&] {
            py::gil_scoped_release release;
            return ngi::read_exr(p, &names);
        }();
        return py::make_tuple(from_image(std::move(img)), names);
    }, py::arg("path"), "An OpenEXR file -> (float32 [C, H, W], channel names in that order).");
    m.def("write_exr", [](const py::object& path, const py::object& image, bool half,
                          const std::vector<std::string>& channel_names) {
        const std::string p = path_string(path, "write_exr: path");
        ngi::Image img = to_image(image, "write_exr: image");
        py::gil_scoped_release release;
        ngi::write_exr(p, img, half ? ngi::ExrPixelType::Half : ngi::ExrPixelType::Float, channel_names);
    }, py::arg("path"), py::arg("image"), py::arg("half") = true, py::arg("channel_names") = std::vector<std::string>{},
       "ZIP-compressed OpenEXR; half clamps finite values to +-65504; names default to Y / R,G,B / R,G,B,A / c0..");
    m.def("read_png", [](const py::object& path, bool srgb) {
        const std::string p = path_string(path, "read_png: path");
        ngi::Image img = [&] {
            py::gil_scoped_release release;
            return ngi::read_png(p, png_encoding(srgb));
        }();
        return from_image(std::move(img));
    }, py::arg("path"), py::arg("srgb") = false, "8/16-bit PNG -> float32 [C, H, W] in [0, 1] (srgb: decode sRGB).");
    m.def("write_png", [](const py::object& path, const py::object& image, bool srgb) {
        const std::string p = path_string(path, "write_png: path");
        ngi::Image img = to_image(image, "write_png: image");
        py::gil_scoped_release release;
        ngi::write_png(p, img, png_encoding(srgb));
    }, py::arg("path"), py::arg("image"), py::arg("srgb") = false,
       "8-bit PNG from [C, H, W] (C = 1..4) in [0, 1] (clamped; NaN -> 0); srgb: encode with the sRGB OETF.");

    m.def("compare_images", [](const DeviceRef& device, const py::object& a, const py::object& b, double data_range) {
        ngi::Image ia = to_image(a, "compare_images: a"), ib = to_image(b, "compare_images: b");
        const ngi::Device& dev = device->get("compare_images");
        ngi::ImageMetrics r = [&] {
            py::gil_scoped_release release;
            return ngi::compare_images(dev, ia, ib, data_range);
        }();
        py::dict d;
        d["mse"] = r.mse;
        d["psnr"] = number_or_none(r.psnr);
        d["ssim"] = number_or_none(r.ssim);
        if (!r.psnr_note.empty()) d["psnr_note"] = r.psnr_note;
        if (!r.ssim_note.empty()) d["ssim_note"] = r.ssim_note;
        return d;
    }, py::arg("device"), py::arg("a"), py::arg("b"), py::arg("data_range") = 1.0, R"doc(
MSE, PSNR (dB) and SSIM of two [C, H, W] images on the device, as scikit-image computes them (Wang et al.: 11 x 11
Gaussian, sigma 1.5, K1 0.01, K2 0.03, population covariances). A dict {'mse', 'psnr', 'ssim'}: psnr is inf for
identical images; a value that is undefined is None with a 'psnr_note' / 'ssim_note' saying why (images below
11 x 11, data_range 0). Non-finite values or values beyond 1e15 are an InputError.)doc");
}

}  // namespace ngi_py
