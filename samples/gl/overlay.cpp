#include "overlay.hpp"

#include <vector>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wsign-compare"
#include <stb/stb_easy_font.h>
#pragma GCC diagnostic pop

namespace ngi_gl {
namespace {
const char* kVs = R"(#version 330 core
layout(location = 0) in vec2 a_pos;
uniform vec2 u_window;
uniform vec2 u_origin;
uniform float u_scale;
void main() {
    vec2 p = u_origin + a_pos * u_scale;
    gl_Position = vec4(2.0 * p.x / u_window.x - 1.0, 1.0 - 2.0 * p.y / u_window.y, 0.0, 1.0);
}
)";
const char* kFs = R"(#version 330 core
uniform vec4 u_colour;
out vec4 o_colour;
void main() { o_colour = u_colour; }
)";
}  // namespace

Overlay::Overlay() {
    program_ = make_program("overlay", kVs, kFs);
    glGenVertexArrays(1, &vao_);
    glGenBuffers(1, &vbo_);
    glBindVertexArray(vao_);
    glBindBuffer(GL_ARRAY_BUFFER, vbo_);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 2 * sizeof(float), nullptr);
    glBindVertexArray(0);
    check_gl("creating the overlay");
}

Overlay::~Overlay() {
    glDeleteBuffers(1, &vbo_);
    glDeleteVertexArrays(1, &vao_);
    glDeleteProgram(program_);
}

void Overlay::draw(const std::string& text, int x, int y, float scale, int window_w, int window_h) {
    // stb_easy_font writes quads of 4 vertices (x, y, z, colour: 16 bytes each); GL core has no quads, so each
    // becomes two triangles.
    std::vector<char> buffer(text.size() * 300 + 1024);
    std::string copy = text;
    const int quads = stb_easy_font_print(0, 0, copy.data(), nullptr, buffer.data(), int(buffer.size()));
    std::vector<float> tri;
    tri.reserve(std::size_t(quads) * 12);
    auto vtx = [&](int q, int k) {
        const float* v = reinterpret_cast<const float*>(buffer.data() + (std::size_t(q) * 4 + k) * 16);
        tri.push_back(v[0]);
        tri.push_back(v[1]);
    };
    for (int q = 0; q < quads; ++q)
        for (int k : {0, 1, 2, 0, 2, 3}) vtx(q, k);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glUseProgram(program_);
    glUniform2f(glGetUniformLocation(program_, "u_window"), float(window_w), float(window_h));
    glUniform1f(glGetUniformLocation(program_, "u_scale"), scale);
    glBindVertexArray(vao_);
    glBindBuffer(GL_ARRAY_BUFFER, vbo_);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(tri.size() * sizeof(float)), tri.data(), GL_STREAM_DRAW);
    // A dark shadow one pixel down-right, then the text: readable on any image.
    glUniform2f(glGetUniformLocation(program_, "u_origin"), float(x + 1), float(y + 1));
    glUniform4f(glGetUniformLocation(program_, "u_colour"), 0.0f, 0.0f, 0.0f, 1.0f);
    glDrawArrays(GL_TRIANGLES, 0, GLsizei(tri.size() / 2));
    glUniform2f(glGetUniformLocation(program_, "u_origin"), float(x), float(y));
    glUniform4f(glGetUniformLocation(program_, "u_colour"), 1.0f, 1.0f, 0.6f, 1.0f);
    glDrawArrays(GL_TRIANGLES, 0, GLsizei(tri.size() / 2));
    glBindVertexArray(0);
    check_gl("drawing the overlay");
}

}  // namespace ngi_gl
