#pragma once
// Face profiling (Zhu et al., "Face Alignment Across Large Poses: A 3D
// Solution", CVPR 2016, as 300W-LP was made for 3DDFA): the image of a face
// turned further than it was photographed, made from the photograph and the
// face model fitted to it, so that large-pose training and evaluation faces
// carry their labels along.
//
// With the fitted mesh X (identity a, expressions b) at the photographed pose
// (R, t) and at the turned pose (R', t), each output pixel p takes the source
// pixel s(p):
//   - on the head: p lies in triangle T of the turned projection, nearest to
//     the camera (z-buffer), with barycentric weights w; s(p) = sum_i w_i
//     pi(R X_i + t), the same surface point in the photograph. When T was
//     hidden there (turned away or behind another part), the photograph has
//     no texture for it: a hole, filled from around it (Telea's inpainting)
//     and counted;
//   - elsewhere: a piecewise affine warp of the background, fixed at the
//     image border, taking the photographed head's outline (the convex hull
//     of its projection) to where the turned head puts those points.
// Turning a face further in the direction it already looks reveals little
// that was hidden; turning it back across the front reveals its far side,
// mostly holes.

#include "core/camera.hpp"
#include "expression/face_warp.hpp"
#include "facetrack/face_model.hpp"
#include "fit/face_fitter.hpp"
#include "fit/pose.hpp"

#include <opencv2/core.hpp>

#include <Eigen/Core>

#include <random>
#include <string>
#include <vector>

namespace facetrack::profile {

struct ProfiledFace {
    cv::Mat image;              ///< the turned face, same size and type as the source
    double hidden_share = 0.0;  ///< of the head's output pixels, the share whose surface was hidden in the source
};

/// `identity`: FaceModel::identityCount() values; `expression`: native
/// weights (expressionNames() order, or empty); `photographed` and `turned`:
/// poses in the fit's convention (fit/pose.hpp), expressions ignored.
/// `turnedExpression`: the output face's native weights, when they differ
/// from the photograph's (the mesh X' of the output then has them).
/// Throws Error on a source that is not 8-bit grey or colour.
ProfiledFace profileFace(const FaceModel& model, const cv::Mat& source, const core::Camera& camera, const std::vector<float>& identity,
                         const std::vector<float>& expression, const fit::FaceParams& photographed, const fit::FaceParams& turned,
                         const std::vector<float>& turnedExpression = {});

struct ProfiledCopy {
    cv::Mat image;
    fit::FaceParams label;  ///< the turned pose, the photograph's expressions
};

/// `tries` copies of a labelled photograph turned further the way it looks
/// (either way when |yaw| < 3 deg) to |yaw| uniform in [max(|yaw| + 10, 25),
/// 85] deg; copies whose head is more than 15 % hidden surface are dropped,
/// and a face already past 75 deg gets none.
std::vector<ProfiledCopy> profiledCopies(const FaceModel& model, const cv::Mat& source, const core::Camera& camera,
                                         const std::vector<float>& identity, const std::vector<float>& expression,
                                         const fit::FaceParams& label, int tries, std::mt19937& rng);

/// Expression warping: `count` copies of a labelled photograph at its own pose with its
/// expression changed, each pixel of the head carried by the mesh's displacement (profileFace),
/// the label exact: the photograph's weights with the change. A copy either moves one named
/// group of shapes to a weight uniform in [0, 0.9] ("brows_down" browDown_L/R, "inner_brows_up",
/// "brows_up" browInnerUp and browOuterUp, "pucker"; then every shape warping may raise by its
/// native name, e.g. "mouthFrown_L", and a left/right pair by its stem, "mouthFrown": the list is
/// expressionCopyGroups()), or, as the group "captured", takes a real face's weights from
/// `captures` (readArkitCaptures) in place of the photograph's. `groups` names those drawn from,
/// alike; empty: all (and "captured" when captures are given). Shapes that open the mouth or the
/// eyes, the look shapes and the model's extras never rise above the photograph's: it shows no
/// mouth's inside (the label's `expressions`: native indices in its order; copies more than 15 %
/// hidden dropped). The 68 points barely follow most of these shapes and no teacher sees some
/// (cheekPuff, noseSneer, cheekSquint, jawForward), so copies whose shapes moved by a known amount
/// teach a net to read them from the texture. Throws Error for a group name it does not know.
std::vector<ProfiledCopy> expressionCopies(const FaceModel& model, const cv::Mat& source, const core::Camera& camera,
                                           const std::vector<float>& identity, const std::vector<int>& expressions,
                                           const fit::FaceParams& label, int count, std::mt19937& rng,
                                           const std::vector<std::string>& groups = {},
                                           const std::vector<std::vector<float>>& captures = {});

/// The group names expressionCopies() knows for this face model (without "captured").
std::vector<std::string> expressionCopyGroups(const FaceModel& model);

/// Real faces' expressions: every `every`-th frame of each Live Link Face CSV in `directory`
/// (../shared/data/arkit: iPhone ARKit captures), as native weights in the face model's order
/// (a shape the captures lack, 0). Throws Error when the folder has no CSV.
std::vector<std::vector<float>> readArkitCaptures(const FaceModel& model, const std::string& directory, int every = 1);

/// A head turn as a clip: the photograph at yaw y0 turned, `stepDeg` a frame,
/// to +80 deg and back to y0, then to -80 deg and back. Each leg stops at its
/// last frame whose head is at most 15 % hidden surface (turning a face back
/// across the front soon hides too much: such a face turns one way only).
/// The first frame is the photograph's own pose. Throws Error unless stepDeg is
/// in [0.5, 20].
std::vector<ProfiledCopy> turnSequence(const FaceModel& model, const cv::Mat& source, const core::Camera& camera,
                                       const std::vector<float>& identity, const std::vector<float>& expression,
                                       const fit::FaceParams& label, double stepDeg);

/// Native expression weights (FaceModel::expressionNames() order) from weights
/// of the expressions `ids` (indices into those names); the others 0.
std::vector<float> nativeWeights(const FaceModel& model, const std::vector<int>& ids, const Eigen::VectorXd& weights);

/// A photograph's annotated 68 points carried to its copy at `turned`: each
/// point keeps its displacement from the label's projected landmark in patch
/// pixels (cnn/landmark_net.hpp); the jaw's projected points follow the
/// turned silhouette. `basis`: expression::landmarkBasis for the label's expressions.
fit::Landmarks2d carriedLandmarks(const expression::WarpLayout& layout, const fit::FitBasis& basis, const Eigen::VectorXd& identity,
                                  const core::Camera& camera, const fit::FaceParams& label, const fit::Landmarks2d& landmarks,
                                  const fit::FaceParams& turned);

/// The pose turned by `yawDeg` about the camera's vertical axis through the
/// model origin: R' = R_y(yaw) R, t' = t.
fit::FaceParams turnedBy(const fit::FaceParams& params, double yawDeg);

}  // namespace facetrack::profile
