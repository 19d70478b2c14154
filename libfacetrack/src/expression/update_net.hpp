#pragma once
// One stage of the CNN cascade (thesis 4.4): a net (patch_net.hpp) regressing,
// from the face texture warped at the current parameters (face_warp.hpp), the
// update that takes those parameters to the face's own.
//
// Its output, for E expressions in the layout's order, is the update
// u = (dw, dc, db), 6 + E numbers, with
// c = R c_0 + t the face centre (WarpLayout::centre c_0) in the camera frame:
//   dw  (3): the angle-axis of R_face R_start^T, so R_face = R(dw) R_start;
//   dc  (3): (c_face - c_start) / z(c_start), the centre's move over its depth;
//   db  (E): b_face - b_start.
// Turning about the centre rather than the model origin (behind the face)
// keeps a turn from looking like a shift.

#include "expression/face_warp.hpp"
#include "nn/patch_net.hpp"

namespace facetrack::expression {

/// A tracked face's public pose and native weights as the cascade's parameters: `expressions`
/// (indices into the native weights, the layout's order; one missing from `native` reads 0).
/// No allocation once params.expression has their size.
void readParams(const HeadPose& pose, const std::vector<float>& native, const std::vector<int>& expressions, fit::FaceParams& params);

/// The update u(start -> face) defined above.
Eigen::VectorXd updateBetween(const WarpLayout& layout, const fit::FaceParams& start, const fit::FaceParams& face);

/// params <- the update applied: R(dw) R, c + z(c) dc, b + db clamped to [0, 1].
void applyUpdate(const WarpLayout& layout, const Eigen::VectorXd& update, fit::FaceParams& params);

/// The update of the mirrored face (the camera's x negated, the patch flipped left to right; the
/// canonical layout is the mirror-symmetric mean face): output i is sign_i u_{order_i}. The
/// rotation M R M, M = diag(-1, 1, 1), has the angle-axis (w_x, -w_y, -w_z), the centre moves by
/// (-c_x, c_y, c_z) (it lies on the face's mirror plane), and left and right expressions swap.
/// train_stage.py mirrors its samples the same way.
struct UpdateMirror {
    std::vector<int> order;
    Eigen::VectorXd sign;
};

/// The mirror of the update over `expressions` (native names, the layout's order). Throws Error
/// when a sided expression's partner (fit::mirrorName) is not among them.
UpdateMirror updateMirror(const std::vector<std::string>& expressions);

/// What one face's refinement reuses from frame to frame.
struct RefineWork {
    Eigen::Matrix3Xd identity_shape;  ///< fit::shapeWithIdentity of the anchors
    Eigen::Matrix3Xd anchors3d;
    Eigen::Matrix2Xd anchors;
    cv::Mat patch;
    cv::Mat mirrored;        ///< the patch flipped, when the update is mirror-averaged
    Eigen::VectorXd update;  ///< the mirror-averaged update
};

/// `rounds` rounds of: warp at params, predict (a net of 6 + E outputs), apply (a stage trained on its
/// own residuals' range converges by repeating). work.identity_shape must be set.
/// With `mirror`, the net (of batch 2) reads the patch and the patch flipped, and the update applied
/// is their mean, u = (f(P) + M f(flip P)) / 2, M the mirror above: the face and its mirror image
/// then read as mirror images of each other, whatever asymmetry the net learned.
/// False (params then meaningless) when the face left the space in front of the
/// camera or a value stopped being finite.
bool refine(const WarpLayout& layout, nn::PatchNet& net, const cv::Mat& grey, const core::Camera& camera, fit::FaceParams& params,
            int rounds, RefineWork& work, const UpdateMirror* mirror = nullptr);

}  // namespace facetrack::expression
