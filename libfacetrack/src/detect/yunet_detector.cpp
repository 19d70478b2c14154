#include "detect/yunet_detector.hpp"

#include "core/box.hpp"

#include "core/image.hpp"
#include "detect/downscale.hpp"
#include "facetrack/error.hpp"

#include <algorithm>
#include <cmath>

namespace facetrack::detect {

namespace {
constexpr float kNmsThreshold = 0.3f;
constexpr int kTopK = 5000;
// YuNet 2022mar scores featureless frames (black, noise) up to about 0.81
// with one frame-sized box at a 320 px input, yet finds nothing in them at
// 240 px; and a real face between two anchor sizes can score as low as 0.75
// at one input size and 1.0 at another. So a detection below kSureScore is
// kept only when a second look at kSecondLookScale of the size confirms it.
constexpr float kSureScore = 0.9f;
constexpr float kSecondLookScale = 0.75f;
constexpr float kSameFaceIou = 0.5f;
}  // namespace

YuNetDetector::YuNetDetector(const std::string& modelPath, const DetectorConfig& config) : path_(modelPath), config_(config) {
    try {
        net_ = cv::FaceDetectorYN::create(path_, "", cv::Size(320, 320), config_.min_score, kNmsThreshold, kTopK);
    } catch (const cv::Exception& e) {
        throw Error("cannot load YuNet model '" + path_ + "': " + e.what());
    }
    if (net_.empty()) throw Error("cannot load YuNet model '" + path_ + "'");
}

std::vector<Detection> YuNetDetector::run(const cv::Mat& image, float scale) {
    net_->setInputSize(image.size());
    cv::Mat faces;
    net_->detect(image, faces);
    std::vector<Detection> detections;
    for (int i = 0; i < faces.rows; ++i) {
        // Row: x, y, w, h, 5 landmark (x, y) pairs, score; in `image` pixels.
        const float* row = faces.ptr<float>(i);
        const float score = row[14];
        if (!std::isfinite(score) || score < config_.min_score || !(row[2] > 0.f && row[3] > 0.f)) continue;
        detections.push_back({toFrame(row[0], row[1], row[2], row[3], scale), std::clamp(score, 0.f, 1.f)});
    }
    return detections;
}

std::vector<Detection> YuNetDetector::detect(const ImageView& frame) {
    const cv::Mat bgr = core::toBgr(frame);
    const Downscaled first = downscale(bgr, config_.detect_width);
    std::vector<Detection> detections = run(first.image, first.scale);

    const bool unsure = std::any_of(detections.begin(), detections.end(), [](const Detection& d) { return d.score < kSureScore; });
    if (unsure) {
        const int secondWidth = std::max(kMinDetectSide, static_cast<int>(first.image.cols * kSecondLookScale));
        const Downscaled second = downscale(bgr, secondWidth);
        const auto secondLook = run(second.image, second.scale);
        std::vector<Detection> confirmed;
        for (auto d : detections) {
            bool sure = d.score >= kSureScore;
            for (const auto& c : secondLook) {
                if (core::intersectionOverUnion(d.box, c.box) < kSameFaceIou) continue;
                sure = true;
                d.score = std::max(d.score, c.score);
            }
            if (sure) confirmed.push_back(d);
        }
        detections = std::move(confirmed);
    }
    return sortAndLimit(std::move(detections), config_.max_faces);
}

}  // namespace facetrack::detect
