#pragma once
// Both detectors work on a frame no wider than DetectorConfig::detect_width,
// padded (right and bottom, so boxes keep their coordinates) to at least
// kMinDetectSide on each side: YuNet's pooling layers fail on tinier inputs.

#include "facetrack/detector.hpp"

#include <opencv2/core.hpp>

#include <vector>

namespace facetrack::detect {

constexpr int kMinDetectSide = 64;

struct Downscaled {
    cv::Mat image;
    float scale = 1.f;  ///< image size / frame size
};

Downscaled downscale(const cv::Mat& frame, int maxWidth);

/// A box (x, y, w, h) found in the downscaled image, in frame pixels.
Box toFrame(float x, float y, float w, float h, float scale);

/// Highest score first, at most maxFaces.
std::vector<Detection> sortAndLimit(std::vector<Detection> detections, int maxFaces);

}  // namespace facetrack::detect
