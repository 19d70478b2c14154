#include "detect/cascade_detector.hpp"

#include "core/image.hpp"
#include "detect/downscale.hpp"
#include "facetrack/error.hpp"

#include <opencv2/imgproc.hpp>

namespace facetrack::detect {

namespace {
constexpr int kMinNeighbors = 3;
constexpr double kScaleStep = 1.1;
constexpr int kMinFaceSize = 24;
}  // namespace

CascadeDetector::CascadeDetector(const std::string& cascadePath, const DetectorConfig& config) : path_(cascadePath), config_(config) {
    bool loaded = false;
    try {
        loaded = cascade_.load(path_);
    } catch (const cv::Exception& e) {
        throw Error("cannot load face cascade '" + path_ + "': " + e.what());
    }
    if (!loaded) throw Error("cannot load face cascade '" + path_ + "' (missing or not a cascade file)");
}

std::vector<Detection> CascadeDetector::detect(const ImageView& frame) {
    cv::Mat buffer;
    const Downscaled small = downscale(core::toGray(frame, buffer), config_.detect_width);
    cv::Mat equalized;
    cv::equalizeHist(small.image, equalized);
    std::vector<cv::Rect> rects;
    std::vector<int> neighbours;
    cascade_.detectMultiScale(equalized, rects, neighbours, kScaleStep, kMinNeighbors, 0, cv::Size(kMinFaceSize, kMinFaceSize));
    std::vector<Detection> detections;
    for (std::size_t i = 0; i < rects.size(); ++i) {
        const auto& r = rects[i];
        const float n = static_cast<float>(neighbours[i]);
        detections.push_back({toFrame(float(r.x), float(r.y), float(r.width), float(r.height), small.scale), n / (n + kMinNeighbors)});
    }
    return sortAndLimit(std::move(detections), config_.max_faces);
}

}  // namespace facetrack::detect
