#include "detect/downscale.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace facetrack::detect {

Downscaled downscale(const cv::Mat& frame, int maxWidth) {
    Downscaled out{frame, 1.f};
    if (maxWidth > 0 && frame.cols > maxWidth) {
        out.scale = static_cast<float>(maxWidth) / static_cast<float>(frame.cols);
        const int height = std::max(1, static_cast<int>(std::lround(frame.rows * out.scale)));
        cv::resize(frame, out.image, cv::Size(maxWidth, height), 0, 0, cv::INTER_AREA);
    }
    const int padRight = std::max(0, kMinDetectSide - out.image.cols);
    const int padBottom = std::max(0, kMinDetectSide - out.image.rows);
    if (padRight > 0 || padBottom > 0) {
        cv::copyMakeBorder(out.image, out.image, 0, padBottom, 0, padRight, cv::BORDER_CONSTANT, cv::Scalar::all(0));
    }
    return out;
}

Box toFrame(float x, float y, float w, float h, float scale) { return {x / scale, y / scale, (x + w) / scale, (y + h) / scale}; }

std::vector<Detection> sortAndLimit(std::vector<Detection> detections, int maxFaces) {
    std::stable_sort(detections.begin(), detections.end(), [](const Detection& a, const Detection& b) { return a.score > b.score; });
    if (maxFaces >= 0 && detections.size() > static_cast<std::size_t>(maxFaces)) detections.resize(maxFaces);
    return detections;
}

}  // namespace facetrack::detect
