#pragma once
// cv::Mat -> facetrack::ImageView, for applications that hold frames in OpenCV.

#include "facetrack/error.hpp"
#include "facetrack/image.hpp"

#include <opencv2/core.hpp>

namespace facetrack::tools {

/// A view of an 8-bit grey, BGR or BGRA cv::Mat (no copy: the Mat must outlive its use).
inline ImageView viewOf(const cv::Mat& mat) {
    if (mat.depth() != CV_8U || (mat.channels() != 1 && mat.channels() != 3 && mat.channels() != 4) || mat.dims != 2) {
        throw Error("viewOf: expected an 8-bit grey, BGR or BGRA image");
    }
    const PixelFormat format = mat.channels() == 1 ? PixelFormat::Gray8 : mat.channels() == 3 ? PixelFormat::Bgr8 : PixelFormat::Bgra8;
    return ImageView{mat.data, mat.cols, mat.rows, mat.step[0], format};
}

}  // namespace facetrack::tools
