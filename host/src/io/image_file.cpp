// read_image / write_image: one entry point for the three formats, chosen by extension.
#include "base/file_util.hpp"
#include "ngi/error.hpp"
#include "ngi/image_io.hpp"
#include "ngi/tensor.hpp"

namespace ngi {

Image read_image(const std::string& path) {
    const std::string ext = detail::lower_extension(path);
    if (ext == ".exr") return read_exr(path);
    if (ext == ".png") return read_png(path);
    if (ext != ".npy")
        throw InputError("read " + path + ": unknown image format '" + ext + "' (use .exr, .png or .npy)");
    Tensor t = read_npy(path);
    std::vector<int> s = t.shape;
    if (s.size() == 4 && s[0] == 1) s.erase(s.begin());
    if (s.size() == 2) s.insert(s.begin(), 1);
    if (s.size() != 3 || s[0] < 1 || s[1] < 1 || s[2] < 1)
        throw InputError("read " + path + ": an image array has shape [H, W], [C, H, W] or [1, C, H, W], not " +
                         shape_string(t.shape));
    Image img;
    img.channels = s[0];
    img.height = s[1];
    img.width = s[2];
    img.data = std::move(t.data);
    return img;
}

void write_image(const std::string& path, const Image& image) {
    const std::string ext = detail::lower_extension(path);
    if (ext == ".exr") return write_exr(path, image, ExrPixelType::Float);
    if (ext == ".png") return write_png(path, image);
    if (ext != ".npy")
        throw InputError("write " + path + ": unknown image format '" + ext + "' (use .exr, .png or .npy)");
    Tensor t({image.channels, image.height, image.width});
    if (t.data.size() != image.data.size())
        throw InputError("write " + path + ": invalid image (" + std::to_string(image.width) + "x" +
                         std::to_string(image.height) + "x" + std::to_string(image.channels) + " with " +
                         std::to_string(image.data.size()) + " values)");
    t.data = image.data;
    write_npy(path, t);
}

}  // namespace ngi
