// Shows ngi's display image (W x H x 3 planar, tone-mapped, sRGB-encoded) in the window, scaled to fit its aspect.
#pragma once
#include <ngi/image.hpp>

#include "gl_context.hpp"

namespace ngi_gl {

class Presenter {
public:
    Presenter();
    ~Presenter();
    Presenter(const Presenter&) = delete;
    Presenter& operator=(const Presenter&) = delete;
    void draw(const ngi::Image& display, int window_w, int window_h);
private:
    GLuint program_ = 0, vao_ = 0, tex_ = 0;
};

}  // namespace ngi_gl
