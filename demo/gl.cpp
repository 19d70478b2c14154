#include "gl.hpp"

#include "facetrack/error.hpp"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <vector>

namespace facetrack::demo {

namespace {

std::string& lastGlfwError() {
    static std::string message;
    return message;
}

void onGlfwError(int, const char* description) { lastGlfwError() = description ? description : "unknown"; }

/// Throws Error with the info log when a shader's compile or a program's link failed.
void throwUnless(GLuint object, GLenum status, void (*getiv)(GLuint, GLenum, GLint*),
                 void (*getInfoLog)(GLuint, GLsizei, GLsizei*, GLchar*), void (*destroy)(GLuint), const std::string& what) {
    GLint ok = 0;
    getiv(object, status, &ok);
    if (ok) return;
    char log[2048] = {};
    getInfoLog(object, sizeof log, nullptr, log);
    destroy(object);
    throw Error(what + ": " + log);
}

GLuint compileShader(GLenum type, const char* source, const std::string& name) {
    const GLuint shader = glCreateShader(type);
    glShaderSource(shader, 1, &source, nullptr);
    glCompileShader(shader);
    throwUnless(shader, GL_COMPILE_STATUS, glGetShaderiv, glGetShaderInfoLog, glDeleteShader,
                name + (type == GL_VERTEX_SHADER ? " vertex" : " fragment") + " shader");
    return shader;
}

}  // namespace

GLuint linkProgram(const char* vertexSource, const char* fragmentSource, const std::string& name) {
    const GLuint vs = compileShader(GL_VERTEX_SHADER, vertexSource, name);
    const GLuint fs = compileShader(GL_FRAGMENT_SHADER, fragmentSource, name);
    const GLuint program = glCreateProgram();
    glAttachShader(program, vs);
    glAttachShader(program, fs);
    glLinkProgram(program);
    glDeleteShader(vs);
    glDeleteShader(fs);
    throwUnless(program, GL_LINK_STATUS, glGetProgramiv, glGetProgramInfoLog, glDeleteProgram, name + " shader program");
    return program;
}

void throwOnGlError(const char* what) {
    const GLenum error = glGetError();
    if (error != GL_NO_ERROR) throw Error(std::string("OpenGL error ") + std::to_string(error) + " in " + what);
}

GlContext::GlContext(int width, int height, const std::string& title, bool visible, int samples)
    : visible_(visible), width_(width), height_(height) {
    if (width <= 0 || height <= 0) throw Error("window size must be positive");
    glfwSetErrorCallback(onGlfwError);
    if (!glfwInit()) {
        throw Error("cannot open a window (" + lastGlfwError() +
                    "). No display: run on a desktop, or headless with 'xvfb-run -a facetrack_demo --headless ...'");
    }
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_VISIBLE, visible ? GLFW_TRUE : GLFW_FALSE);
    glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
    window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
    if (!window_) {
        glfwTerminate();
        throw Error("cannot create an OpenGL 3.3 core window (" + lastGlfwError() + ")");
    }
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(visible ? 1 : 0);
    if (samples < 0) {
        const std::string renderer = rendererName();
        const bool software = renderer.find("llvmpipe") != std::string::npos || renderer.find("softpipe") != std::string::npos;
        samples = software ? 0 : 4;
    }
    GLint most = 0;
    glGetIntegerv(GL_MAX_SAMPLES, &most);
    samples_ = std::min(samples, static_cast<int>(most));

    glGenRenderbuffers(1, &msaa_colour_);
    glBindRenderbuffer(GL_RENDERBUFFER, msaa_colour_);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples_, GL_RGBA8, width, height);
    glGenRenderbuffers(1, &msaa_depth_);
    glBindRenderbuffer(GL_RENDERBUFFER, msaa_depth_);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples_, GL_DEPTH_COMPONENT24, width, height);
    glGenFramebuffers(1, &msaa_fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, msaa_fbo_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, msaa_colour_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, msaa_depth_);
    const GLenum msaa_status = glCheckFramebufferStatus(GL_FRAMEBUFFER);

    glGenRenderbuffers(1, &resolved_colour_);
    glBindRenderbuffer(GL_RENDERBUFFER, resolved_colour_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
    glGenFramebuffers(1, &resolved_fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, resolved_fbo_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, resolved_colour_);
    const GLenum resolved_status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    if (msaa_status != GL_FRAMEBUFFER_COMPLETE || resolved_status != GL_FRAMEBUFFER_COMPLETE) {
        throw Error("the offscreen framebuffer is incomplete on " + rendererName());
    }
    throwOnGlError("creating the offscreen framebuffer");
}

GlContext::~GlContext() {
    if (!window_) return;
    glDeleteFramebuffers(1, &msaa_fbo_);
    glDeleteFramebuffers(1, &resolved_fbo_);
    glDeleteRenderbuffers(1, &msaa_colour_);
    glDeleteRenderbuffers(1, &msaa_depth_);
    glDeleteRenderbuffers(1, &resolved_colour_);
    glfwDestroyWindow(window_);
    glfwTerminate();
}

std::string GlContext::rendererName() const {
    const auto text = [](GLenum name) {
        const auto* s = reinterpret_cast<const char*>(glGetString(name));
        return std::string(s ? s : "?");
    };
    return text(GL_RENDERER) + ", OpenGL " + text(GL_VERSION);
}

void GlContext::beginFrame(float r, float g, float b) {
    glBindFramebuffer(GL_FRAMEBUFFER, msaa_fbo_);
    glViewport(0, 0, width_, height_);
    glClearColor(r, g, b, 1.f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

void GlContext::endFrame() {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, msaa_fbo_);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, resolved_fbo_);
    glBlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    if (visible_) {
        // Scaled into the window, keeping the aspect ratio (the window may have been resized).
        int fw = 0, fh = 0;
        glfwGetFramebufferSize(window_, &fw, &fh);
        const double scale = std::min(static_cast<double>(fw) / width_, static_cast<double>(fh) / height_);
        const int w = static_cast<int>(width_ * scale), h = static_cast<int>(height_ * scale);
        const int x = (fw - w) / 2, y = (fh - h) / 2;
        glBindFramebuffer(GL_READ_FRAMEBUFFER, resolved_fbo_);
        glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
        glViewport(0, 0, fw, fh);
        glClearColor(0.f, 0.f, 0.f, 1.f);
        glClear(GL_COLOR_BUFFER_BIT);
        glBlitFramebuffer(0, 0, width_, height_, x, y, x + w, y + h, GL_COLOR_BUFFER_BIT, GL_LINEAR);
        glfwSwapBuffers(window_);
    }
    throwOnGlError("drawing the frame");
}

cv::Mat GlContext::readPixels() const {
    cv::Mat rgba(height_, width_, CV_8UC4);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, resolved_fbo_);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data);
    cv::Mat bgr;
    cv::cvtColor(rgba, bgr, cv::COLOR_RGBA2BGR);
    cv::flip(bgr, bgr, 0);  // GL's first row is the bottom one
    return bgr;
}

}  // namespace facetrack::demo
