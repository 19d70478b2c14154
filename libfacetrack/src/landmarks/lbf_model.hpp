#pragma once
// Local binary features landmark model (Ren, Cao, Wei, Sun, "Face Alignment at
// 3000 FPS via Regressing Local Binary Features", CVPR 2014), as plain data.
//
// A cascade of stages t = 1..T. In stage t each landmark l has a random forest
// whose trees map the image around the current shape S^{t-1} to one leaf each;
// the reached leaves form the binary feature Phi^t. A global linear regression
// gives the shape increment in the mean-shape frame,
//   S^t = S^{t-1} + M^{-1} (W^t Phi^t),
// where M is the similarity taking S^{t-1} to the mean shape.
//
// Feature points (thesis, ch. 4): every point a split compares is a convex
// combination of three "anchors" of the current shape: the 68 landmarks and
// the padded hull points c + (1 + padding)(x_h - c), c the landmarks' centroid,
// h in hull_indices. A point therefore always lies inside the current shape's
// convex hull scaled by (1 + padding): background never drives a split.

#include <Eigen/Core>

#include "core/shape2d.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace facetrack::landmarks {

// The regression works on the shared 68-point shape (core/shape2d.hpp).
using core::kLandmarks;
using core::Shape68;

/// p = w0 a0 + w1 a1 + (1 - w0 - w1) a2, anchors indexing [landmarks..., padded hull points...].
struct FeaturePoint {
    std::array<std::uint8_t, 3> anchors{};
    std::array<float, 2> weights{};
};

/// Goes left when I(a) - I(b) < threshold (grey levels).
struct Split {
    FeaturePoint a, b;
    std::int16_t threshold = 0;
};

/// Regression rows in float, row (tree * 2^depth + leaf), 2 x 68 columns.
using RegressionRows = Eigen::Matrix<float, Eigen::Dynamic, 2 * kLandmarks, Eigen::RowMajor>;

struct LbfStage {
    /// kLandmarks * trees_per_landmark trees, landmark-major; each a complete
    /// binary tree of (2^depth - 1) splits in breadth-first order.
    std::vector<Split> splits;
    /// Row (tree * 2^depth + leaf) holds that leaf's contribution to the
    /// 2 x 68 increment, x0 y0 x1 y1 ... in the mean-shape frame, as
    /// row_scale[row] * regression(row, c). Eight bits per value: a face reads
    /// 68 K rows per stage scattered over megabytes, so a quarter of the bytes
    /// of float is most of the run time saved; the error is at most half a
    /// step, 1/254 of the row's largest value.
    Eigen::Matrix<std::int8_t, Eigen::Dynamic, 2 * kLandmarks, Eigen::RowMajor> regression;
    std::vector<float> row_scale;

    /// Stores `rows` quantised (scale = the row's largest magnitude / 127).
    void setRegression(const RegressionRows& rows);
    /// The rows back in float.
    RegressionRows regressionRows() const;
};

/// Where the initial shape goes for a detector's box: mean shape in box
/// coordinates, (0, 0) the box's top-left and (1, 1) its bottom-right.
struct BoxPrior {
    std::string detector;  ///< "yunet", "cascade"
    Shape68 shape;
};

struct LbfModel {
    int trees_per_landmark = 0;
    int tree_depth = 0;
    float hull_padding = 0.f;
    std::vector<std::uint8_t> hull_indices;  ///< landmarks on the mean shape's convex hull
    Shape68 mean_shape;                      ///< centred, unit RMS radius
    std::vector<BoxPrior> box_priors;
    std::vector<LbfStage> stages;

    int leavesPerTree() const { return 1 << tree_depth; }
    int splitsPerTree() const { return (1 << tree_depth) - 1; }
    int treesPerStage() const { return kLandmarks * trees_per_landmark; }
    int anchorCount() const { return kLandmarks + static_cast<int>(hull_indices.size()); }
};

constexpr char kLbfMagic[] = "FTLBF68 ";
/// 1: regression rows as half floats; 2: as int8 with a float scale per row.
/// Both are read; version 2 is written.
constexpr std::uint32_t kLbfVersion = 2;

/// Throws Error (prefixed by `what`) unless sizes and indices are consistent.
void validate(const LbfModel& model, const std::string& what);
void writeLbfModel(const std::string& path, const LbfModel& model);
LbfModel readLbfModel(const std::string& path);

}  // namespace facetrack::landmarks
