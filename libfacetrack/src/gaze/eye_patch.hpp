#pragma once
// The canonical eye patch (Wang, Shi, Xia, Chai 2016, sec. 4.1): the eye cut
// out of the grey frame by a similarity transform that puts its outer corner
// at (kOuterX, kCornerY) and its inner corner at (kInnerX, kCornerY), so every
// eye is the same size and upright. The subject's left eye is mirrored
// (x -> -x before the similarity) so that in every patch the outer corner is
// on the left and the nose on the right: one classifier serves both eyes.
//
// Intensities are normalised per patch to zero mean and unit deviation,
// which takes out exposure and contrast.

#include "facetrack/geometry.hpp"

#include <opencv2/core.hpp>

namespace facetrack::gaze {

constexpr int kPatchWidth = 40;
constexpr int kPatchHeight = 28;
constexpr float kOuterX = 6.f;
constexpr float kInnerX = 34.f;
constexpr float kCornerY = 14.f;
/// Patch pixels from one eye corner to the other.
constexpr float kEyeWidth = kInnerX - kOuterX;

enum class Eye { Left, Right };  ///< the subject's own

/// The eye's corners among the 68 landmarks: left 45 (outer), 42 (inner); right 36, 39.
int outerCorner(Eye eye);
int innerCorner(Eye eye);

struct EyePatch {
    cv::Mat pixels;                ///< kPatchHeight x kPatchWidth, CV_32F, normalised
    cv::Matx23f image_from_patch;  ///< patch pixel -> frame pixel
    cv::Matx23f patch_from_image;
    float image_px_per_patch_px = 1.f;
    bool mirrored = false;
};

/// Cuts `eye`'s patch from an 8-bit grey frame (bilinear; pixels outside the
/// frame repeat its border); `out`'s buffer is reused.
/// Returns false when the corners
/// are not finite or less than 2 px apart (no eye to cut).
bool cutEyePatch(const cv::Mat& gray, const Landmarks68& landmarks, Eye eye, EyePatch& out);
/// The same from two corner positions (the trainer's and the tests' entry).
bool cutEyePatch(const cv::Mat& gray, Point2 outer, Point2 inner, bool mirror, EyePatch& out);

Point2 toPatch(const EyePatch& patch, Point2 image);
Point2 toImage(const EyePatch& patch, Point2 inPatch);

}  // namespace facetrack::gaze
