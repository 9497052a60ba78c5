#include "gl_context.hpp"

#include <GLFW/glfw3.h>

#include <vector>

namespace ngi_gl {
namespace {
std::string g_glfw_error = "unknown GLFW error";
void on_glfw_error(int code, const char* text) { g_glfw_error = std::string(text) + " (GLFW error " + std::to_string(code) + ")"; }
}  // namespace

GlContext::GlContext(int width, int height, bool visible, const std::string& title) {
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit()) throw GlError("no OpenGL 3.3 core context: glfwInit failed: " + g_glfw_error);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_VISIBLE, visible ? GLFW_TRUE : GLFW_FALSE);
    glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
    window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
    if (!window_) {
        glfwTerminate();
        throw GlError("no OpenGL 3.3 core context: " + g_glfw_error);
    }
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(0);  // measure the frame, not the display's refresh
    if (epoxy_gl_version() < 33) {
        glfwDestroyWindow(window_);
        glfwTerminate();
        throw GlError("no OpenGL 3.3 core context: the context offers GL " + std::to_string(epoxy_gl_version()));
    }
}

GlContext::~GlContext() {
    if (window_) glfwDestroyWindow(window_);
    glfwTerminate();
}

std::string GlContext::renderer() const {
    return std::string(reinterpret_cast<const char*>(glGetString(GL_RENDERER))) + ", GL " +
           reinterpret_cast<const char*>(glGetString(GL_VERSION));
}

void check_gl(const char* what) {
    const GLenum e = glGetError();
    if (e != GL_NO_ERROR) throw GlError(std::string(what) + ": GL error 0x" + [e] {
        char b[16];
        std::snprintf(b, sizeof b, "%04x", unsigned(e));
        return std::string(b);
    }());
}

static GLuint compile(const char* name, GLenum type, const char* src) {
    const GLuint s = glCreateShader(type);
    glShaderSource(s, 1, &src, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        GLint len = 0;
        glGetShaderiv(s, GL_INFO_LOG_LENGTH, &len);
        std::vector<char> log(std::size_t(len) + 1);
        glGetShaderInfoLog(s, len, nullptr, log.data());
        glDeleteShader(s);
        throw GlError(std::string(name) + (type == GL_VERTEX_SHADER ? " vertex" : " fragment") +
                      " shader does not compile: " + log.data());
    }
    return s;
}

GLuint make_program(const char* name, const char* vertex_src, const char* fragment_src) {
    const GLuint vs = compile(name, GL_VERTEX_SHADER, vertex_src), fs = compile(name, GL_FRAGMENT_SHADER, fragment_src);
    const GLuint p = glCreateProgram();
    glAttachShader(p, vs);
    glAttachShader(p, fs);
    glLinkProgram(p);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        GLint len = 0;
        glGetProgramiv(p, GL_INFO_LOG_LENGTH, &len);
        std::vector<char> log(std::size_t(len) + 1);
        glGetProgramInfoLog(p, len, nullptr, log.data());
        glDeleteProgram(p);
        throw GlError(std::string(name) + " program does not link: " + log.data());
    }
    return p;
}

}  // namespace ngi_gl
