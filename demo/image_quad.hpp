#pragma once
// Draws a BGR or BGRA image into a viewport as a textured quad: the camera
// panel and the HUD. Needs a current GL context.

#include "gl.hpp"

#include <opencv2/core.hpp>

namespace facetrack::demo {

class ImageQuad {
public:
    ImageQuad();
    ~ImageQuad();
    ImageQuad(const ImageQuad&) = delete;
    ImageQuad& operator=(const ImageQuad&) = delete;

    /// Uploads `image` (CV_8UC3 BGR, or CV_8UC4 BGRA blended by its alpha) and
    /// draws it stretched over the viewport (x, y, width, height), GL's
    /// bottom-left origin. `mirror` flips it left-right.
    void draw(const cv::Mat& image, int x, int y, int width, int height, bool mirror);

private:
    GLuint program_ = 0, vao_ = 0, texture_ = 0;
};

}  // namespace facetrack::demo
