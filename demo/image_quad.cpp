#include "image_quad.hpp"

#include "facetrack/error.hpp"

namespace facetrack::demo {

namespace {

// A full-viewport quad from gl_VertexID: no vertex buffer needed.
const char* kVertexShader = R"(#version 330 core
uniform bool mirror;
out vec2 uv;
void main() {
    vec2 corner = vec2(float(gl_VertexID & 1), float((gl_VertexID >> 1) & 1));
    uv = vec2(mirror ? 1.0 - corner.x : corner.x, 1.0 - corner.y);
    gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}
)";

const char* kFragmentShader = R"(#version 330 core
uniform sampler2D image;
in vec2 uv;
out vec4 fragment;
void main() { fragment = texture(image, uv).bgra; }
)";

}  // namespace

ImageQuad::ImageQuad() {
    program_ = linkProgram(kVertexShader, kFragmentShader, "image");
    glGenVertexArrays(1, &vao_);
    glGenTextures(1, &texture_);
    glBindTexture(GL_TEXTURE_2D, texture_);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    throwOnGlError("creating the image quad");
}

ImageQuad::~ImageQuad() {
    glDeleteTextures(1, &texture_);
    glDeleteVertexArrays(1, &vao_);
    glDeleteProgram(program_);
}

void ImageQuad::draw(const cv::Mat& image, int x, int y, int width, int height, bool mirror) {
    if (image.empty() || (image.type() != CV_8UC3 && image.type() != CV_8UC4)) {
        throw Error("ImageQuad::draw needs a BGR or BGRA 8-bit image");
    }
    const bool alpha = image.channels() == 4;
    glBindTexture(GL_TEXTURE_2D, texture_);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glPixelStorei(GL_UNPACK_ROW_LENGTH, static_cast<GLint>(image.step / image.elemSize()));
    // Uploaded as RGB(A) and swizzled in the shader: the bytes are BGR(A).
    glTexImage2D(GL_TEXTURE_2D, 0, alpha ? GL_RGBA8 : GL_RGB8, image.cols, image.rows, 0, alpha ? GL_RGBA : GL_RGB, GL_UNSIGNED_BYTE,
                 image.data);
    glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
    glViewport(x, y, width, height);
    if (alpha) {
        glEnable(GL_BLEND);
        glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    }
    glUseProgram(program_);
    glUniform1i(glGetUniformLocation(program_, "mirror"), mirror ? 1 : 0);
    glUniform1i(glGetUniformLocation(program_, "image"), 0);
    glActiveTexture(GL_TEXTURE0);
    glBindVertexArray(vao_);
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    glBindVertexArray(0);
    glDisable(GL_BLEND);
    throwOnGlError("drawing an image");
}

}  // namespace facetrack::demo
