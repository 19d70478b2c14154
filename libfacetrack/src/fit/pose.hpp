#pragma once
// The fit's unknowns for one face in one frame, and their conversion to the
// public HeadPose.

#include "facetrack/result.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace facetrack::fit {

/// Pose (R, t): x_camera = R x_model + t, with R = R(omega) R_0 (fit_basis.hpp),
/// omega an angle-axis vector, t in cm; plus the fitted expression weights b.
struct FaceParams {
    Eigen::Matrix<double, 6, 1> pose = Eigen::Matrix<double, 6, 1>::Zero();  ///< (omega, t)
    Eigen::VectorXd expression;                                              ///< FitBasis order, in [0, 1]

    auto omega() const { return pose.head<3>(); }
    auto translation() const { return pose.tail<3>(); }
};

/// R(omega), the rotation from the frontal frame.
Eigen::Matrix3d rotationOf(const Eigen::Vector3d& omega);

/// (pitch, yaw, roll) in degrees as result.hpp defines them, from R(omega).
Eigen::Vector3d eulerDegrees(const Eigen::Vector3d& omega);

/// The angle-axis omega of a pose given as (pitch, yaw, roll) degrees.
Eigen::Vector3d omegaFromEuler(const Eigen::Vector3d& eulerDeg);

/// The public pose of a fitted face.
HeadPose headPoseOf(const FaceParams& params);

/// The inverse: the pose part of params (omega, t) of a public pose; expressions untouched.
void poseParamsOf(const HeadPose& pose, FaceParams& params);

/// The public pose of a rotation x_camera = q x_model (a unit quaternion, R_0
/// included) and a translation in mm.
HeadPose headPoseOf(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translationMm);

}  // namespace facetrack::fit
