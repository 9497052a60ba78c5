// Text on top of the displayed frame (stb_easy_font: quads from a built-in bitmap-free vector font), drawn in
// window pixels with one small program.
#pragma once
#include <string>

#include "gl_context.hpp"

namespace ngi_gl {

class Overlay {
public:
    Overlay();
    ~Overlay();
    Overlay(const Overlay&) = delete;
    Overlay& operator=(const Overlay&) = delete;
    // Draws `text` (newlines allowed) at (x, y) window pixels from the top left, scaled by `scale`.
    void draw(const std::string& text, int x, int y, float scale, int window_w, int window_h);
private:
    GLuint program_ = 0, vao_ = 0, vbo_ = 0;
};

}  // namespace ngi_gl
