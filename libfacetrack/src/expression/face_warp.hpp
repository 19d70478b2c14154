#pragma once
// The face texture in a canonical 2D space (thesis 4.4): the CNN cascade's input.
//
// Anchor points on the model's face, laid out in a square patch by the mean
// face's frontal projection, are triangulated there, padded with a ring of
// boundary points and the patch's border. Given the anchors' projections into
// a frame, each patch pixel p inside canonical triangle (i, j, k) with
// barycentric weights (a, b, c) samples the frame at a u_i + b u_j + c u_k
// (a piecewise affine warp); a ring point's frame position is the least-squares
// affine map of the anchors, canonical -> frame, applied to it.

#include "core/camera.hpp"
#include "fit/fit_basis.hpp"
#include "fit/pose.hpp"
#include "model/face_model_data.hpp"

#include <opencv2/core.hpp>

#include <Eigen/Core>

#include <array>
#include <vector>

namespace facetrack::expression {

struct WarpLayout {
    int size = 0;             ///< the patch is size x size pixels
    fit::PointBasis anchors;  ///< the anchors' rows, for `expressions`
    /// The mean face's mean anchor (frontal frame, cm): the cascade's updates
    /// turn the face about it (update_net.hpp), so that a turn and a shift look different.
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    Eigen::Matrix2Xd canonical;                 ///< 2 x (anchors + boundary), patch pixels
    std::vector<std::array<int, 3>> triangles;  ///< over the columns of `canonical`
    /// Per patch pixel (row-major): its triangle, -1 for none, and its barycentric weights.
    std::vector<int> pixel_triangle;
    std::vector<Eigen::Vector3f> pixel_weights;
    /// (A^T A)^-1 A^T for A = [canonical anchors^T 1]: times the anchors' frame
    /// positions (transposed), the least-squares affine map canonical -> frame.
    Eigen::Matrix<double, 3, Eigen::Dynamic> affine_solve;

    int anchorCount() const { return anchors.slotCount(); }
    int boundaryCount() const { return static_cast<int>(canonical.cols()) - anchorCount(); }
};

/// Anchors: the face-region vertices inside the 68 landmark vertices' hull
/// (frontal projection, grown 10 %), one per cell of a `grid` x `grid` grid.
/// `expressions`: indices into data.expressions the anchors' rows carry.
WarpLayout makeWarpLayout(const model::FaceModelData& data, const std::vector<int>& expressions, int size = 64, int grid = 14);

/// The anchors' frame positions (2 x anchors, pixels) for identity a (empty:
/// the mean face) and params (expression in `expressions` order, or empty).
Eigen::Matrix2Xd projectAnchors(const WarpLayout& layout, const Eigen::VectorXd& identity, const core::Camera& camera,
                                const fit::FaceParams& params);
/// The same from the anchors' identity shape (fit::shapeWithIdentity of
/// layout.anchors), into `out` through `work`: no allocation once they are sized.
void projectAnchors(const WarpLayout& layout, const Eigen::Matrix3Xd& identityShape, const core::Camera& camera,
                    const fit::FaceParams& params, Eigen::Matrix3Xd& work, Eigen::Matrix2Xd& out);

/// Warps the grey frame into `patch` (CV_8U, size x size; bilinear, edge
/// pixels repeated past the frame's border). Throws Error when `frame` is not
/// 8-bit grey or `anchors` has the wrong size. No allocation once `patch` is sized.
void warpFace(const WarpLayout& layout, const cv::Mat& frame, const Eigen::Matrix2Xd& anchors, cv::Mat& patch);

}  // namespace facetrack::expression
