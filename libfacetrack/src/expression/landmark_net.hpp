#pragma once
// The cascade's last CNN (thesis 4.4): 2D displacements of the 68 landmarks
// from where the current parameters project them, regressed from the face
// patch warped at those parameters (face_warp.hpp).
//
// With p_i the projection of landmark i at the parameters (the learned
// convention's landmark points, jaw points on the silhouette: fit/face_fitter.hpp)
// and L the linear part of the least-squares affine map canonical -> frame of
// the anchors (WarpLayout::affine_solve), the net (patch_net.hpp) regresses
//   d_i = L^-1 (q_i - p_i),   i = 0..67, outputs (x_0, y_0, x_1, ..., y_67),
// in patch pixels, and the landmarks are q_i = p_i + L d_i. In patch pixels a
// displacement does not depend on the face's place, size or roll in the frame.

#include "expression/face_warp.hpp"
#include "facetrack/face_model.hpp"
#include "fit/face_fitter.hpp"

namespace facetrack::expression {

constexpr int kLandmarkOutputs = 2 * model::kLandmarkCount;

/// The landmark fit's basis (the model's convention applied) for the
/// expressions `expressions` (indices into the model's names): the cascade's.
fit::FitBasis landmarkBasis(const FaceModel& model, const std::vector<int>& expressions);

/// L above, from the anchors' frame positions.
Eigen::Matrix2d patchToFrame(const WarpLayout& layout, const Eigen::Matrix2Xd& anchors);

/// p above: the landmarks `params` (expressions in the basis's order) project
/// to, from the basis's identity shape (fit::shapeWithIdentity), through
/// `slots`: no allocation once it is sized.
fit::Landmarks2d projectedLandmarks(const fit::FitBasis& basis, const Eigen::Matrix3Xd& identityShape, const core::Camera& camera,
                                    const fit::FaceParams& params, Eigen::Matrix3Xd& slots);

/// d above for landmarks q (what a net is trained on).
Eigen::VectorXd displacementsOf(const Eigen::Matrix2d& patchToFrame, const fit::Landmarks2d& projected, const fit::Landmarks2d& q);

/// q above from the net's outputs d.
fit::Landmarks2d displaced(const Eigen::Matrix2d& patchToFrame, const fit::Landmarks2d& projected, const Eigen::VectorXd& d);

}  // namespace facetrack::expression
