#include "presenter.hpp"

#include <algorithm>
#include <cmath>

#include <algorithm>
#include <vector>

namespace ngi_gl {
namespace {
const char* kVs = R"(#version 330 core
out vec2 v_uv;
void main() {
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
    v_uv = vec2(p.x, 1.0 - p.y);   // ngi's row 0 is the top
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
)";
const char* kFs = R"(#version 330 core
in vec2 v_uv;
uniform sampler2D u_image;
out vec4 o_colour;
void main() { o_colour = vec4(texture(u_image, v_uv).rgb, 1.0); }   // already sRGB-encoded by ngi's tone map
)";
}  // namespace

Presenter::Presenter() {
    program_ = make_program("present", kVs, kFs);
    glGenVertexArrays(1, &vao_);
    glGenTextures(1, &tex_);
    glBindTexture(GL_TEXTURE_2D, tex_);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);  // show ngi's pixels as they are
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    check_gl("creating the presenter");
}

Presenter::~Presenter() {
    glDeleteTextures(1, &tex_);
    glDeleteVertexArrays(1, &vao_);
    glDeleteProgram(program_);
}

void Presenter::draw(const ngi::Image& display, int window_w, int window_h) {
    // Interleave the planar display image for the texture upload (N^2 x 3 floats: display only, not ngi's input).
    std::vector<float> rgb(display.plane() * 3);
    for (std::size_t i = 0; i < display.plane(); ++i)
        for (int c = 0; c < 3; ++c) rgb[i * 3 + c] = display.data[c * display.plane() + i];
    glActiveTexture(GL_TEXTURE0);  // the G-buffer pass leaves another unit active
    glBindTexture(GL_TEXTURE_2D, tex_);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB32F, display.width, display.height, 0, GL_RGB, GL_FLOAT, rgb.data());
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, window_w, window_h);
    glClearColor(0.05f, 0.05f, 0.05f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    // The largest rectangle of the image's aspect that fits the window, centred.
    const double scale = std::min(double(window_w) / display.width, double(window_h) / display.height);
    const int vw = std::max(1, int(std::lround(display.width * scale))), vh = std::max(1, int(std::lround(display.height * scale)));
    glViewport((window_w - vw) / 2, (window_h - vh) / 2, vw, vh);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glUseProgram(program_);
    glActiveTexture(GL_TEXTURE0);
    glUniform1i(glGetUniformLocation(program_, "u_image"), 0);
    glBindVertexArray(vao_);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glViewport(0, 0, window_w, window_h);
    check_gl("presenting the frame");
}

}  // namespace ngi_gl
