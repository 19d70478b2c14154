#pragma once
// Fitting pose, expression and (over a window of frames) identity to 68 2D
// landmarks, with Ceres (thesis ch. 4; Cao et al.'s "3D shape regression"
// fitting without the depth term):
//
//   min  sum_i rho(|pi(R X_i(a, b) + t) - u_i|^2 / s^2)
//        + w_l2 sum_j f_j b_j^2 + w_t |b - b_prev|^2 + |W_p (p - p_prev)|^2,   b in [0, 1]
//
// over the pose p = (omega, t) and expression b, with u_i the landmarks, s the
// face's size in pixels (faceScale), rho a Huber loss, f_j the learned prior's
// factors (FitBasis::expression_prior; 1 without one). The 17 jaw landmarks are not
// tied to fixed vertices: each is matched to the silhouette vertex among its
// contour candidates (nearestContour), re-chosen as the pose changes.

#include "core/camera.hpp"
#include "fit/costs.hpp"
#include "fit/fit_basis.hpp"
#include "fit/pose.hpp"

#include <Eigen/Cholesky>

#include <array>
#include <memory>
#include <vector>

namespace facetrack::fit {

using Landmarks2d = Eigen::Matrix<double, 2, model::kLandmarkCount>;
using ContourSlots = std::array<int, model::kContourLandmarkCount>;

struct FitSettings {
    double huber = 0.05;                 ///< robust loss scale, in face sizes (faceScale)
    double expression_l2 = 1e-3;         ///< w_l2 (TrackerConfig::expression_prior scales it)
    double expression_temporal = 5e-3;   ///< w_t
    double rotation_temporal = 1e-3;     ///< per rad^2
    double translation_temporal = 1e-5;  ///< per cm^2
    double identity_prior = 2e-4;        ///< w_id |a|^2 during identity calibration
    int cold_iterations = 40;
    int warm_iterations = 5;
    /// The jaw's side points weigh 1 up to |yaw| jaw_turn_from_deg, jaw_turned_weight from
    /// jaw_turn_to_deg on, linearly between (jawSideWeight).
    double jaw_turn_from_deg = 20.0;
    double jaw_turn_to_deg = 40.0;
    double jaw_turned_weight = 0.25;
};

/// The jaw's side points: 0-5 and 11-16, beside the chin.
bool isJawSide(int landmark);

/// The weight of the jaw's side points in the fit of a face at `yawDeg` (the
/// current estimate's, taken when the contour is chosen). Past ~30 deg of yaw
/// those points and the model's silhouette part ways, and their pull reads the
/// turn short: the 300-W training faces' annotated points fit 0.94x the inner
/// points' yaw there (1.01-1.07x below 30 deg), the exact points of face
/// profiling's turned copies 0.94x the turn (1.00 without the jaw's sides).
/// Weighed less there, they still hold the face's width and pull the turn less
/// (docs/fitting.md, "Turns").
double jawSideWeight(const FitSettings& settings, double yawDeg);

struct FitReport {
    double residual = 0.0;  ///< RMS landmark distance after the fit, in face sizes (faceScale)
    ContourSlots contour{};
    Landmarks2d projected = Landmarks2d::Zero();  ///< the fitted face's landmarks (pixels)
    int iterations = 0;
};

/// Single-threaded, silent Ceres options; `tolerance` on the relative cost and
/// parameter changes (the landmark fit: 1e-5, far below the landmarks' noise;
/// tighter ones only add iterations).
ceres::Solver::Options solverOptions(int iterations, ceres::LinearSolverType solver, double tolerance = 1e-5);

/// Outer-eye-corner distance (points 36 and 45), the 300-W face size.
double eyeCornerDistance(const Landmarks2d& points);

/// s above: the eye-corner distance, but at least half of sqrt(w h) of the
/// points' box (and 1 px). Turned past ~45 deg the eye corners close up (the
/// ratio falls from 0.5-0.7 on 300-W's faces to 0.2-0.4), and the residual in
/// their distance would drop a well-fitted face.
double faceScale(const Landmarks2d& points);

using Pose6 = Eigen::Matrix<double, 6, 1>;  ///< (omega, t) as in FaceParams

/// X_s = base_s + D_s b for every slot (3 x S, frontal frame, cm), into `x`
/// (no allocation once `x` has the size).
void slotPositions(const PointBasis& basis, const Eigen::Matrix3Xd& base, const Eigen::VectorXd& expression, Eigen::Matrix3Xd& x);

/// The 68 landmarks slot positions `x` project to under `pose`, jaw points at `contour`.
Landmarks2d projectSlots(const FitBasis& basis, const Eigen::Matrix3Xd& x, const core::Camera& camera, const Pose6& pose,
                         const ContourSlots& contour);

/// For each jaw landmark, the candidate on the silhouette: the one whose
/// projection reaches furthest along the image direction of the landmark's
/// outward axis (FitBasis::contour_outward). A path swept across the jaw
/// reaches that extreme where it turns out of view. This is how a rendered
/// face's jaw landmarks fall (the synthetic tests and face profiling use it).
/// Candidates more than 1.5 cm from the landmark along the outline (the model's
/// y for the sides, x for the chin) are left out: they lie off the path.
ContourSlots silhouetteContourAt(const FitBasis& basis, const Eigen::Matrix3Xd& x, const core::Camera& camera, const Pose6& pose);

/// For each jaw landmark, the candidate whose projection is nearest the
/// observed point: the correspondence the fit uses. On real faces the
/// candidate paths (snapped to mesh vertices) wander off the outline in
/// places, and the observed point, not the pure geometry, says where on the
/// outline the annotator's jaw point lies.
ContourSlots nearestContourAt(const FitBasis& basis, const Eigen::Matrix3Xd& x, const core::Camera& camera, const Pose6& pose,
                              const Landmarks2d& observed);

/// The same three for a base shape and fitted parameters (they compute the slot
/// positions, allocating: for tests and tools, not per frame).
Landmarks2d projectLandmarks(const FitBasis& basis, const Eigen::Matrix3Xd& base, const core::Camera& camera, const FaceParams& params,
                             const ContourSlots& contour);
ContourSlots silhouetteContour(const FitBasis& basis, const Eigen::Matrix3Xd& base, const core::Camera& camera, const FaceParams& params);

/// Fits one face frame by frame. Holds a Ceres problem (for cold fits) built
/// once and re-solved, and the warm fit's buffers, sized once. Not copyable:
/// the problem points into the fitter.
class FaceFitter {
public:
    FaceFitter(std::shared_ptr<const FitBasis> basis, const FitSettings& settings);
    ~FaceFitter();
    FaceFitter(const FaceFitter&) = delete;
    FaceFitter& operator=(const FaceFitter&) = delete;

    /// Identity coefficients a (empty: the mean face).
    void setIdentity(const Eigen::VectorXd& identity);
    const Eigen::VectorXd& identity() const { return identity_; }
    const Eigen::Matrix3Xd& base() const { return base_; }
    const FitBasis& basis() const { return *basis_; }
    const FitSettings& settings() const { return settings_; }

    /// Fits `params` to `observed` (pixels). Cold: params are initialised from
    /// the points. Warm: params hold the previous frame's fit, the start and
    /// the target of the temporal prior.
    FitReport fit(const core::Camera& camera, const Landmarks2d& observed, FaceParams& params, bool warm);

private:
    FaceParams initialParams(const Landmarks2d& observed) const;
    int solve(int iterations);
    /// The same objective minimised by a few Levenberg-Marquardt steps that call
    /// the same cost functions directly: Ceres's Solve() spends ~150 us setting
    /// up per call, three times the maths of a warm frame (docs/fitting.md).
    int solveWarm(int iterations);
    double objective(Eigen::MatrixXd* jacobian);  // the warm objective at pose_, expression_

    void chooseContour(bool nearest, FitReport& report);

    std::shared_ptr<const FitBasis> basis_;
    FitSettings settings_;
    Eigen::VectorXd identity_;
    Eigen::Matrix3Xd base_;

    // What the costs read through pointers. current_'s pose and expression are
    // the Ceres parameter blocks: sized once, never reallocated.
    core::Camera camera_;
    Landmarks2d observed_ = Landmarks2d::Zero();
    double scale_ = 1.0;
    std::array<double, model::kLandmarkCount> point_weights_;  // PointsCost's factor per landmark
    FaceParams current_;
    Pose6 previous_pose_;
    Eigen::VectorXd previous_expression_;
    Eigen::VectorXd expression_weights_;  // w_l2 per expression (FitBasis::expressionPriorWeights)
    Eigen::Matrix3Xd slots_;              // slot positions at current_.expression

    std::unique_ptr<ceres::Problem> problem_;
    PointsCost* landmarks_ = nullptr;

    // solveWarm's buffers, sized once.
    Eigen::VectorXd residuals_;
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> jacobian_pose_, jacobian_expression_;
    Eigen::MatrixXd jacobian_, normal_, damped_;
    Eigen::LDLT<Eigen::MatrixXd> ldlt_;
    Eigen::VectorXd gradient_, step_, expression_before_step_;
};

/// One frame of the identity calibration window.
struct CalibrationFrame {
    core::Camera camera;
    Landmarks2d observed;
    FaceParams params;  ///< start; refined in place
    ContourSlots contour{};
};

/// The identity a shared by all frames, fitted jointly with each frame's pose
/// and expression (w_id |a|^2 keeps it near the mean; the contour stays as
/// given). Frames should show varied poses: depth and identity trade off in a
/// single view.
Eigen::VectorXd calibrateIdentity(const FitBasis& basis, std::vector<CalibrationFrame>& frames, const FitSettings& settings);

}  // namespace facetrack::fit
