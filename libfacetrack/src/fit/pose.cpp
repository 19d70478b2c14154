#include "fit/pose.hpp"

#include "core/math.hpp"

#include "fit/fit_basis.hpp"

#include <algorithm>
#include <cmath>

namespace facetrack::fit {

// Relative to the frontal frame, R(omega) = Rz(roll) Rx(pitch) Ry(-yaw) about
// the camera axes (x right, y down, z forward): yaw first, then pitch, then roll.
// The signs make pitch > 0 chin down, yaw > 0 a turn to the image's right and
// roll > 0 a clockwise tilt in the image (y points down).

namespace {
constexpr double kDeg = core::kRadiansPerDegree;
}

Eigen::Matrix3d rotationOf(const Eigen::Vector3d& omega) {
    const double angle = omega.norm();
    if (angle < 1e-12) return Eigen::Matrix3d::Identity();
    return Eigen::AngleAxisd(angle, omega / angle).toRotationMatrix();
}

Eigen::Vector3d eulerDegrees(const Eigen::Vector3d& omega) {
    const Eigen::Matrix3d r = rotationOf(omega);
    const double pitch = std::asin(std::clamp(r(2, 1), -1.0, 1.0));
    const double yaw = -std::atan2(-r(2, 0), r(2, 2));
    const double roll = std::atan2(-r(0, 1), r(1, 1));
    return Eigen::Vector3d(pitch, yaw, roll) / kDeg;
}

Eigen::Vector3d omegaFromEuler(const Eigen::Vector3d& eulerDeg) {
    const Eigen::Vector3d e = eulerDeg * kDeg;
    const Eigen::Matrix3d r = (Eigen::AngleAxisd(e.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(e.x(), Eigen::Vector3d::UnitX()) *
                               Eigen::AngleAxisd(-e.y(), Eigen::Vector3d::UnitY()))
                                  .toRotationMatrix();
    const Eigen::AngleAxisd aa(r);
    return aa.angle() * aa.axis();
}

HeadPose headPoseOf(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translationMm) {
    const Eigen::Quaterniond q = rotation.normalized();
    const Eigen::AngleAxisd fromFrontal(q.toRotationMatrix() * modelToFrontal().transpose());
    const Eigen::Vector3d euler = eulerDegrees(fromFrontal.angle() * fromFrontal.axis());
    HeadPose pose;
    pose.rotation = {static_cast<float>(q.w()), static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z())};
    pose.euler_deg = {static_cast<float>(euler.x()), static_cast<float>(euler.y()), static_cast<float>(euler.z())};
    pose.translation_mm = {static_cast<float>(translationMm.x()), static_cast<float>(translationMm.y()),
                           static_cast<float>(translationMm.z())};
    // [R t; 0 1], column-major; OpenGL's eye frame negates the camera's y and z rows.
    const Eigen::Matrix3d r = q.toRotationMatrix();
    for (int row = 0; row < 3; ++row) {
        const float flip = row == 0 ? 1.f : -1.f;
        for (int col = 0; col < 3; ++col) {
            pose.camera_from_model[4 * col + row] = static_cast<float>(r(row, col));
            pose.gl_model_view[4 * col + row] = flip * static_cast<float>(r(row, col));
        }
        pose.camera_from_model[12 + row] = static_cast<float>(translationMm[row]);
        pose.gl_model_view[12 + row] = flip * static_cast<float>(translationMm[row]);
    }
    pose.camera_from_model[15] = pose.gl_model_view[15] = 1.f;
    return pose;
}

HeadPose headPoseOf(const FaceParams& params) {
    return headPoseOf(Eigen::Quaterniond(rotationOf(params.omega()) * modelToFrontal()), params.translation() * 10.0);
}

void poseParamsOf(const HeadPose& pose, FaceParams& params) {
    const Eigen::Quaterniond q(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z);
    const Eigen::AngleAxisd r(q.normalized().toRotationMatrix() * modelToFrontal().transpose());
    params.pose.head<3>() = r.angle() * r.axis();
    params.pose.tail<3>() = Eigen::Vector3d(pose.translation_mm.x, pose.translation_mm.y, pose.translation_mm.z) / 10.0;
}

}  // namespace facetrack::fit
