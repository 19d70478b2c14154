#include "core/image.hpp"

#include "facetrack/error.hpp"

#include <opencv2/imgproc.hpp>

#include <limits>
#include <string>

namespace facetrack {

int bytesPerPixel(PixelFormat format) {
    switch (format) {
        case PixelFormat::Gray8: return 1;
        case PixelFormat::Bgr8:
        case PixelFormat::Rgb8: return 3;
        case PixelFormat::Bgra8:
        case PixelFormat::Rgba8: return 4;
    }
    throw Error("unknown pixel format " + std::to_string(static_cast<int>(format)));
}

namespace core {

cv::Mat wrap(const ImageView& view) {
    const int bpp = bytesPerPixel(view.format);
    if (view.data == nullptr) throw Error("invalid image: null pixel pointer");
    if (view.width <= 0 || view.height <= 0) {
        throw Error("invalid image: size " + std::to_string(view.width) + "x" + std::to_string(view.height));
    }
    if (view.width > std::numeric_limits<int>::max() / bpp ||
        view.stride < static_cast<std::size_t>(view.width) * static_cast<std::size_t>(bpp)) {
        throw Error("invalid image: stride " + std::to_string(view.stride) + " bytes is shorter than a row of " +
                    std::to_string(view.width) + " pixels x " + std::to_string(bpp) + " bytes");
    }
    return cv::Mat(view.height, view.width, CV_8UC(bpp), const_cast<std::uint8_t*>(view.data), view.stride);
}

cv::Mat toBgr(const ImageView& view) {
    const cv::Mat src = wrap(view);
    cv::Mat bgr;
    switch (view.format) {
        case PixelFormat::Bgr8: return src;
        case PixelFormat::Gray8: cv::cvtColor(src, bgr, cv::COLOR_GRAY2BGR); break;
        case PixelFormat::Rgb8: cv::cvtColor(src, bgr, cv::COLOR_RGB2BGR); break;
        case PixelFormat::Bgra8: cv::cvtColor(src, bgr, cv::COLOR_BGRA2BGR); break;
        case PixelFormat::Rgba8: cv::cvtColor(src, bgr, cv::COLOR_RGBA2BGR); break;
    }
    return bgr;
}

cv::Mat toGray(const ImageView& view, cv::Mat& gray) {
    const cv::Mat src = wrap(view);
    switch (view.format) {
        case PixelFormat::Gray8: return src;
        case PixelFormat::Bgr8: cv::cvtColor(src, gray, cv::COLOR_BGR2GRAY); break;
        case PixelFormat::Rgb8: cv::cvtColor(src, gray, cv::COLOR_RGB2GRAY); break;
        case PixelFormat::Bgra8: cv::cvtColor(src, gray, cv::COLOR_BGRA2GRAY); break;
        case PixelFormat::Rgba8: cv::cvtColor(src, gray, cv::COLOR_RGBA2GRAY); break;
    }
    return gray;
}

ImageView viewOf(const cv::Mat& mat) {
    if (mat.depth() != CV_8U || (mat.channels() != 1 && mat.channels() != 3)) {
        throw Error("viewOf: expected an 8-bit grey or BGR image");
    }
    return ImageView{mat.data, mat.cols, mat.rows, mat.step[0],
                     mat.channels() == 1 ? PixelFormat::Gray8 : PixelFormat::Bgr8};
}

}  // namespace core
}  // namespace facetrack
