#pragma once
// Running an LbfModel: initial shapes and the regression cascade. Nothing here
// allocates per call.

#include "facetrack/geometry.hpp"
#include "landmarks/lbf_model.hpp"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace facetrack::landmarks {

/// The anchors of a shape: its 68 landmarks, then the padded hull points.
using Anchors = Eigen::Matrix<float, 2, Eigen::Dynamic, Eigen::ColMajor, 2, 256>;

Anchors anchorsOf(const LbfModel& model, const Shape68& shape);

inline Eigen::Vector2f pointOf(const FeaturePoint& p, const Anchors& anchors) {
    return p.weights[0] * anchors.col(p.anchors[0]) + p.weights[1] * anchors.col(p.anchors[1]) +
           (1.f - p.weights[0] - p.weights[1]) * anchors.col(p.anchors[2]);
}

/// Grey level at the pixel nearest p, clamped to the image. (Clamping before
/// rounding keeps the cast in range, also for NaN: it compares false and clamps.)
inline int pixelAt(const cv::Mat& gray, const Eigen::Vector2f& p) {
    const float fx = p.x() > 0.f ? std::min(p.x(), static_cast<float>(gray.cols - 1)) : 0.f;
    const float fy = p.y() > 0.f ? std::min(p.y(), static_cast<float>(gray.rows - 1)) : 0.f;
    return gray.ptr<std::uint8_t>(static_cast<int>(fy + 0.5f))[static_cast<int>(fx + 0.5f)];
}

/// Calls onLeaf(tree, regressionRow) for the leaf each tree of the stage reaches.
template <class OnLeaf>
void traverseStage(const LbfModel& model, const LbfStage& stage, const cv::Mat& gray, const Anchors& anchors, OnLeaf&& onLeaf) {
    const int splitsPerTree = model.splitsPerTree();
    const int trees = model.treesPerStage();
    for (int t = 0; t < trees; ++t) {
        const Split* tree = stage.splits.data() + static_cast<std::size_t>(t) * splitsPerTree;
        int node = 0;
        while (node < splitsPerTree) {
            const Split& s = tree[node];
            const int diff = pixelAt(gray, pointOf(s.a, anchors)) - pixelAt(gray, pointOf(s.b, anchors));
            node = 2 * node + (diff < s.threshold ? 1 : 2);
        }
        onLeaf(t, t * model.leavesPerTree() + (node - splitsPerTree));
    }
}

/// Applies one stage's increment W^t Phi^t to `shape`, in place.
void applyStage(const LbfModel& model, const LbfStage& stage, const cv::Mat& gray, Shape68& shape);

/// The full cascade from an initial shape. `gray` is 8-bit, one channel.
Shape68 alignLandmarks(const LbfModel& model, const cv::Mat& gray, Shape68 shape);

/// How many starts alignFromStarts takes at most: the start and eight shifted copies.
constexpr int kMaxLandmarkStarts = 9;
/// The shift of alignFromStarts' copies, a share of the start's outer-eye-corner distance.
constexpr float kStartShift = 0.04f;

/// The cascade from N starts, averaged (N in 1..kMaxLandmarkStarts):
///   S = (1/N) sum_k align(S_0 + s d_k),  s = kStartShift |p_36 - p_45| of S_0,
/// d_0 = 0, then the unit directions +x, -x, +y, -y and the four diagonals.
/// Why: a tree's leaf flips with a grey level of noise, so one start's answer
/// jumps from frame to frame; starts a few pixels apart reach other leaves and
/// their mean jumps less, and it is a little closer to the truth
/// (docs/landmarks.md: jitter, NME and the cost, N times one start).
Shape68 alignFromStarts(const LbfModel& model, const cv::Mat& gray, const Shape68& start, int starts);
/// Throws Error "`what` must be in 1..kMaxLandmarkStarts" unless `starts` is.
void checkStartCount(int starts, const std::string& what);

/// The initial shape for a detector box: the model's box prior for that
/// detector kind ("yunet", "cascade"), else its first prior.
Shape68 shapeFromBox(const LbfModel& model, const Box& box, const std::string& detector);

}  // namespace facetrack::landmarks
