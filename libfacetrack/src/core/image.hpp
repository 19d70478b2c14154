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
/// `buffer` (reused without reallocating when the size stays the same). The
/// result may be passed back as `buffer`: a wrapped grey frame is never written to.
cv::Mat toGray(const ImageView& view, cv::Mat& buffer);

/// A view of an 8-bit BGR or grey cv::Mat (for tools and tests).
ImageView viewOf(const cv::Mat& mat);

/// True where the CPU has AVX2 and every byte offset into `gray` fits a 32-bit lane: then the
/// patch cuts (warpAffineGray, gaze::cutEyePatch) gather eight sample points at a time.
bool gathersFit(const cv::Mat& gray);

/// patch(u, v) = gray(A (u, v, 1)^T), bilinear, the border repeated: to the
/// byte what cv::warpAffine(gray, patch, A, size, INTER_LINEAR |
/// WARP_INVERSE_MAP, BORDER_REPLICATE) gives, without the scratch memory it
/// allocates on every call. As OpenCV does, the point is rounded to 1/32 px
/// (from A's entries at 1/1024 px) and the four weights, w_00 = (32 - f_x)
/// (32 - f_y) and so on for the fractions f in 32nds, sum to 1024:
///   patch = (sum_k w_k p_k + 512) >> 10.
/// `gray`: 8-bit, one channel, not empty; `patch` is made `size`, CV_8U
/// (reused without reallocating when it already is).
void warpAffineGray(const cv::Mat& gray, const cv::Matx23d& frameFromPatch, cv::Size size, cv::Mat& patch);

}  // namespace facetrack::core
