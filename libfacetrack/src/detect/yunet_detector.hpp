#pragma once
#include "facetrack/detector.hpp"

#include <opencv2/objdetect.hpp>

namespace facetrack::detect {

/// YuNet through cv::FaceDetectorYN, run on a frame downscaled to
/// DetectorConfig::detect_width; unsure detections get a second look at a
/// smaller size (see yunet_detector.cpp).
class YuNetDetector final : public FaceDetector {
public:
    YuNetDetector(const std::string& modelPath, const DetectorConfig& config);
    std::vector<Detection> detect(const ImageView& frame) override;
    std::string kind() const override { return "yunet"; }
    std::string modelPath() const override { return path_; }

private:
    /// Detections in `image`, mapped to frame pixels by 1/scale.
    std::vector<Detection> run(const cv::Mat& image, float scale);

    std::string path_;
    DetectorConfig config_;
    cv::Ptr<cv::FaceDetectorYN> net_;
};

}  // namespace facetrack::detect
