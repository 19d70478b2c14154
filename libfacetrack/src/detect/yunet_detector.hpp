#pragma once
#include "facetrack/detector.hpp"

#include <opencv2/objdetect.hpp>

namespace facetrack::detect {

/// YuNet through cv::FaceDetectorYN, run on a frame downscaled to
/// DetectorConfig::detect_width.
class YuNetDetector final : public FaceDetector {
public:
    YuNetDetector(const std::string& modelPath, const DetectorConfig& config);
    std::vector<Detection> detect(const ImageView& frame) override;
    std::string kind() const override { return "yunet"; }
    std::string modelPath() const override { return path_; }

private:
    std::string path_;
    DetectorConfig config_;
    cv::Ptr<cv::FaceDetectorYN> net_;
};

}  // namespace facetrack::detect
