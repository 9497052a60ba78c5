// The OpenGL 3.3 core context: a GLFW window (hidden for headless runs, e.g. under Xvfb) with libepoxy loading
// the GL entry points, plus the small GL helpers every pass uses (shader programs, error checks).
#pragma once
#include <epoxy/gl.h>

#include <stdexcept>
#include <string>

struct GLFWwindow;

namespace ngi_gl {

// A GL failure: the message names the call or shader that failed.
class GlError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

class GlContext {
public:
    // Throws GlError("no OpenGL 3.3 core context: <GLFW's reason>") when no display or no such context exists.
    GlContext(int width, int height, bool visible, const std::string& title);
    ~GlContext();
    GlContext(const GlContext&) = delete;
    GlContext& operator=(const GlContext&) = delete;
    GLFWwindow* window() const { return window_; }
    std::string renderer() const;  // GL_RENDERER / GL_VERSION
private:
    GLFWwindow* window_ = nullptr;
};

// Compiles and links a program from vertex and fragment sources; GlError with the info log on failure.
GLuint make_program(const char* name, const char* vertex_src, const char* fragment_src);
// GlError naming `what` when glGetError reports anything.
void check_gl(const char* what);

}  // namespace ngi_gl
