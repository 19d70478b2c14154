#include "detect/yunet_detector.hpp"

#include "core/image.hpp"
#include "detect/downscale.hpp"
#include "facetrack/error.hpp"

#include <algorithm>
#include <cmath>

namespace facetrack::detect {

namespace {
constexpr float kNmsThreshold = 0.3f;
constexpr int kTopK = 5000;
}  // namespace

YuNetDetector::YuNetDetector(const std::string& modelPath, const DetectorConfig& config)
    : path_(modelPath), config_(config) {
    try {
        net_ = cv::FaceDetectorYN::create(path_, "", cv::Size(320, 320), config_.min_score, kNmsThreshold, kTopK);
    } catch (const cv::Exception& e) {
        throw Error("cannot load YuNet model '" + path_ + "': " + e.what());
    }
    if (net_.empty()) throw Error("cannot load YuNet model '" + path_ + "'");
}

std::vector<Detection> YuNetDetector::detect(const ImageView& frame) {
    const Downscaled small = downscale(core::toBgr(frame), config_.detect_width);
    net_->setInputSize(small.image.size());
    cv::Mat faces;
    net_->detect(small.image, faces);

    std::vector<Detection> detections;
    for (int i = 0; i < faces.rows; ++i) {
        // Row: x, y, w, h, 5 landmark (x, y) pairs, score.
        const float* row = faces.ptr<float>(i);
        const float score = row[14];
        if (!std::isfinite(score) || score < config_.min_score) continue;
        if (!(row[2] > 0.f && row[3] > 0.f)) continue;
        detections.push_back({{row[0], row[1], row[0] + row[2], row[1] + row[3]}, std::clamp(score, 0.f, 1.f)});
    }
    return finish(std::move(detections), small.scale, config_.max_faces);
}

}  // namespace facetrack::detect
