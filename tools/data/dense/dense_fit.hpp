#pragma once
// Pose, identity and every fitted expression from the teacher's dense points
// (docs/expressions.md): the landmark fit's objective (face_fitter.hpp) over the
// N MediaPipe vertices that have a surface point on the model,
//
//   min  sum_i rho(|pi(R X_i(a, b) + t) - u_i|^2 / s^2) + (N / 68) (sum_j w_j b_j^2 + w_id |a|^2),   b in [0, 1],
//
// X_i = sum_k w_ik V(v_ik) + o_i: surface points (correspondence.hpp). The
// priors scale with N / 68 so that the dense points weigh as much as 68
// landmarks: one network predicts them all, so their errors are not
// independent. w_j is small for the expressions the points observe (the
// landmark fit's rule, fit_basis.hpp) and large for the others, which the
// points cannot tell apart from the pose or the observed ones: the prior
// keeps those near 0 instead of letting them explain the teacher's noise.

#include "core/camera.hpp"
#include "data/dense/correspondence.hpp"
#include "data/dense/mediapipe_mesh.hpp"
#include "fit/face_fitter.hpp"
#include "fit/fit_basis.hpp"
#include "fit/pose.hpp"

#include <Eigen/Core>

#include <array>
#include <vector>

namespace facetrack::dense {

struct DenseFitSettings {
    double huber = 0.05;            ///< in eye-corner distances
    double observable_l2 = 1e-4;    ///< w_j of an observed expression, per 68 points
    double unobservable_l2 = 1e-2;  ///< w_j of the others
    double identity_prior = 2e-4;   ///< w_id, per 68 points and frame
    int iterations = 60;
};

/// What the fit needs besides the frame: the basis of the used points, and
/// which of its slots are the outer eye corners (the face size s and the start).
struct DenseModel {
    fit::PointBasis basis;
    std::vector<bool> observable;           ///< per basis expression
    std::array<int, 2> eye_corner_slots{};  ///< subject's right, left
};

/// The model of the correspondence's used points (slot s = usableVertices()[s],
/// offsets included) for `expressions`. Throws Error when an outer eye corner is not used.
DenseModel denseModel(const model::FaceModelData& data, const Correspondence& correspondence, const std::vector<int>& expressions);

/// Every expression but eyeLook* (the teacher's mesh has no eyeballs): what the labels fit.
std::vector<int> labelledExpressions(const model::FaceModelData& data);

struct DenseFrame {
    core::Camera camera;
    Eigen::Matrix2Xd observed;  ///< 2 x N, pixels, basis slot order
    fit::FaceParams params;     ///< start when `warm`; the result
    double residual = 0.0;      ///< RMS point distance after the fit, eye-corner distances
};

/// Where the teacher puts its points on real faces, relative to the model (the
/// dense counterpart of the landmark convention, tools/train/convention): `frames`
/// fitted with pose and identity only (expressions held near 0 by a strong
/// prior), each point's median residual moved onto the face at its depth,
/// averaged with its mirror point's (`mirror`: slot -> mirror slot); `rounds`
/// times. Adds the offsets to model.basis.neutral and returns them (3 x N,
/// frontal frame, cm). Most faces must be near neutral for this to hold.
Eigen::Matrix3Xd learnTeacherConvention(DenseModel& model, const DenseFitSettings& settings, std::vector<DenseFrame> frames,
                                        const std::vector<int>& mirror, int rounds);

/// Row `row` of the teacher's meshes as a frame: its `vertices` (slot order),
/// the camera of the image's size (60 deg across, as the landmark tools assume).
DenseFrame teacherFrame(const TeacherMeshes& meshes, int row, const std::vector<int>& vertices);

/// Fits one frame's pose and expression with the identity held at `identity`
/// (empty: the mean face). Cold (`warm` false): from a frontal start at the
/// eye corners' depth, pose alone first.
void fitFrame(const DenseModel& model, const DenseFitSettings& settings, const Eigen::VectorXd& identity, DenseFrame& frame, bool warm);

/// The identity shared by `frames`, fitted jointly with each frame's pose and
/// expression (each frame is fitted cold first). Frames hold their results.
Eigen::VectorXd fitIdentity(const DenseModel& model, const DenseFitSettings& settings, std::vector<DenseFrame>& frames);

/// The canonical mesh as a camera sees it: its `vertices` (the used ones, in
/// slot order) aligned onto the model by the correspondence's similarity,
/// turned by `yawDeg`, 60 cm in front of a 640 x 480 camera (60 deg across).
/// A neutral face: the fit's check (it must find no expression).
DenseFrame canonicalFrame(const Correspondence& correspondence, const Eigen::Matrix3Xd& canonical, const std::vector<int>& vertices,
                          double yawDeg);

/// The points' projections under params (pixels).
Eigen::Matrix2Xd projectPoints(const DenseModel& model, const Eigen::VectorXd& identity, const core::Camera& camera,
                               const fit::FaceParams& params);

}  // namespace facetrack::dense
