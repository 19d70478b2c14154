#pragma once
#include "facetrack/detector.hpp"

#include <opencv2/objdetect.hpp>

namespace facetrack::detect {

/// OpenCV's Viola-Jones Haar cascade: the fallback when YuNet's model is
/// absent. Its score is the share of agreeing neighbour windows, n / (n + 3).
class CascadeDetector final : public FaceDetector {
public:
    CascadeDetector(const std::string& cascadePath, const DetectorConfig& config);
    std::vector<Detection> detect(const ImageView& frame) override;
    std::string kind() const override { return "cascade"; }
    std::string modelPath() const override { return path_; }

private:
    std::string path_;
    DetectorConfig config_;
    cv::CascadeClassifier cascade_;
};

}  // namespace facetrack::detect
