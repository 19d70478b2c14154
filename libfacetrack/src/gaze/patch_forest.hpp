#pragma once
// Random forests over simple pixel tests on the normalised eye patch (Wang et
// al. 2016 classify iris pixels this way; Shotton et al. 2011's depth-pixel
// forests are the pattern). Complete binary trees of one depth, stored as
// flat arrays: node i has children 2i+1 and 2i+2; leaves hold `outputs`
// floats (class probabilities, or regressed values), averaged over the trees.

#include <opencv2/core.hpp>

#include <cstdint>
#include <vector>

namespace facetrack::gaze {

/// A test's value at anchor p (the pixel being classified, or the patch
/// origin for a whole-patch regressor); offsets are clamped to the patch.
struct PatchFeature {
    enum Kind : std::uint8_t { Difference = 0, Intensity = 1, Column = 2, Row = 3 };
    std::int8_t ax = 0, ay = 0, bx = 0, by = 0;  ///< I(p + a) - I(p + b); I(p + a); p.x; p.y
    std::uint8_t kind = Difference;
    std::uint8_t reserved[3] = {0, 0, 0};
    float threshold = 0.f;  ///< right child when value >= threshold

    float value(const cv::Mat& patch, int x, int y) const;
};

struct PatchForest {
    int depth = 0;
    int outputs = 0;
    std::vector<PatchFeature> splits;  ///< treeCount() x (2^depth - 1)
    std::vector<float> leaves;         ///< treeCount() x 2^depth x outputs

    int splitsPerTree() const { return (1 << depth) - 1; }
    int leavesPerTree() const { return 1 << depth; }
    int treeCount() const { return depth > 0 ? static_cast<int>(splits.size()) / splitsPerTree() : 0; }
    /// out[0, outputs) = the mean over trees of the leaves reached from (x, y).
    void evaluate(const cv::Mat& patch, int x, int y, float* out) const;
    /// The same as evaluate(patch, x, y, out), read from `padded`: the patch
    /// with at least reach() pixels repeated around it (padPatch). Why: a
    /// classifier evaluates every anchor of a patch, and no read needs its
    /// clamp (the gaze stage about 13 % faster).
    void evaluatePadded(const cv::Mat& padded, int margin, int x, int y, float* out) const;
    /// The largest offset of any test, in pixels along x or y.
    int reach() const;
    /// Throws Error(what: corrupt: ...) when the arrays do not fit the sizes
    /// or hold non-finite values.
    void validate(const char* what) const;
};

/// `patch` (CV_32F) with `margin` pixels repeated around it, into `padded`
/// (allocated once, then reused): for PatchForest::evaluatePadded.
void padPatch(const cv::Mat& patch, int margin, cv::Mat& padded);

}  // namespace facetrack::gaze
