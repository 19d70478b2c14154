#pragma once
// OpenGL 3.3 core for the demo: the GL entry points (libGL exports them on
// Linux, no loader needed), shader helpers, and GlContext, a GLFW window whose
// frames are drawn into an offscreen framebuffer so that the same path serves
// the screen, screenshots and headless runs.

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <opencv2/core.hpp>

#include <string>

struct GLFWwindow;

namespace facetrack::demo {

/// Compiles and links a vertex + fragment shader pair; throws Error with the
/// GL info log when either fails.
GLuint linkProgram(const char* vertexSource, const char* fragmentSource, const std::string& name);

/// Throws Error naming `what` when GL has recorded an error.
void throwOnGlError(const char* what);

/// A GLFW window with an OpenGL 3.3 core context, and a multisampled
/// offscreen framebuffer of the window's size that every frame is drawn into.
class GlContext {
public:
    /// visible = false: a hidden window (headless; still needs an X display,
    /// e.g. xvfb-run). samples: multisampling per pixel; < 0 picks 4 on a GPU
    /// and none on a software rasteriser (llvmpipe), where 4x doubles the
    /// frame time. Throws Error when there is no display or no GL 3.3.
    GlContext(int width, int height, const std::string& title, bool visible, int samples = -1);
    ~GlContext();
    GlContext(const GlContext&) = delete;
    GlContext& operator=(const GlContext&) = delete;

    /// Binds the offscreen framebuffer and clears it.
    void beginFrame(float r, float g, float b);
    /// Resolves the offscreen frame; shows it in the window when visible.
    void endFrame();
    /// The last resolved frame as BGR, top row first.
    cv::Mat readPixels() const;

    GLFWwindow* window() const { return window_; }
    int width() const { return width_; }
    int height() const { return height_; }
    /// "llvmpipe (LLVM 15.0.6, 256 bits), OpenGL 4.5 (Core Profile) Mesa 22.3.6".
    std::string rendererName() const;
    int samples() const { return samples_; }

private:
    GLFWwindow* window_ = nullptr;
    bool visible_ = false;
    int width_ = 0, height_ = 0;
    int samples_ = 0;
    GLuint msaa_fbo_ = 0, msaa_colour_ = 0, msaa_depth_ = 0;
    GLuint resolved_fbo_ = 0, resolved_colour_ = 0;
};

}  // namespace facetrack::demo
