#include "send/avatar_pose.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace facetrack::send {

namespace {
Eigen::Quaternionf toEigen(const Quaternion& q) { return Eigen::Quaternionf(q.w, q.x, q.y, q.z).normalized(); }
Quaternion fromEigen(const Eigen::Quaternionf& q) { return {q.w(), q.x(), q.y(), q.z()}; }
// Camera from model of a face looking straight into the camera: a half turn about x.
const Eigen::Quaternionf kFrontal(0.f, 1.f, 0.f, 0.f);
}  // namespace

Quaternion headFromRest(const HeadPose& pose) { return fromEigen(kFrontal.conjugate() * toEigen(pose.rotation)); }

Quaternion toUnity(const Quaternion& rest) { return {rest.w, rest.x, -rest.y, -rest.z}; }

Quaternion eyeFromRest(const HeadPose& pose, const EyeGaze& eye) {
    // The gaze in the head's frame, then the shortest rotation from +z to it.
    const Eigen::Vector3f camera(eye.direction.x, eye.direction.y, eye.direction.z);
    const Eigen::Vector3f head = toEigen(pose.rotation).conjugate() * camera;
    if (!head.allFinite() || head.norm() < 1e-6f || head.z() <= 0.f) return {};
    return fromEigen(Eigen::Quaternionf::FromTwoVectors(Eigen::Vector3f::UnitZ(), head.normalized()));
}

Quaternion fraction(const Quaternion& q, float s) { return fromEigen(Eigen::Quaternionf::Identity().slerp(s, toEigen(q))); }

Quaternion multiply(const Quaternion& a, const Quaternion& b) { return fromEigen(toEigen(a) * toEigen(b)); }

Vec3 eulerXyzDeg(const Quaternion& rest) {
    const Eigen::Matrix3f r = toEigen(rest).toRotationMatrix();
    // R = Rx(a) Ry(b) Rz(c): r02 = sin b, r12 = -sin a cos b, r22 = cos a cos b, r01 = -cos b sin c, r00 = cos b cos c.
    constexpr float kDeg = 57.29577951308232f;
    const float b = std::asin(std::clamp(r(0, 2), -1.f, 1.f));
    return {std::atan2(-r(1, 2), r(2, 2)) * kDeg, b * kDeg, std::atan2(-r(0, 1), r(0, 0)) * kDeg};
}

}  // namespace facetrack::send
