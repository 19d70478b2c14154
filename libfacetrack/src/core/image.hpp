#pragma once
// ImageView <-> cv::Mat, with the validation every stage relies on.

#include "facetrack/image.hpp"

#include <opencv2/core.hpp>

namespace facetrack::core {

/// Wraps the caller's pixels without copying. Throws Error when the view is
/// invalid (null data, non-positive size, stride shorter than a row).
cv::Mat wrap(const ImageView& view);

/// The frame as 8-bit BGR: wraps when it already is, else converts.
cv::Mat toBgr(const ImageView& view);

/// The frame as 8-bit grey: wraps when it already is, else converts into
/// `buffer` (reused without reallocating when the size stays the same).
cv::Mat toGray(const ImageView& view, cv::Mat& buffer);

/// A view of an 8-bit BGR or grey cv::Mat (for tools and tests).
ImageView viewOf(const cv::Mat& mat);

}  // namespace facetrack::core
