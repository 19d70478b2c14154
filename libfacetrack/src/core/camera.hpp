#pragma once
// The pinhole camera the fit projects through (internal form of CameraConfig).

#include <Eigen/Core>

namespace facetrack::core {

/// u = fx X/Z + cx, v = fy Y/Z + cy, in the camera frame of result.hpp.
struct Camera {
    double fx = 1.0, fy = 1.0;
    double cx = 0.0, cy = 0.0;

    template <class T>
    Eigen::Matrix<T, 2, 1> project(const Eigen::Matrix<T, 3, 1>& p) const {
        return {T(fx) * p.x() / p.z() + T(cx), T(fy) * p.y() / p.z() + T(cy)};
    }
};

/// Square pixels; the focal length `focalPx` when positive, else the one giving
/// `horizontalFovDeg` across the width; the principal point (principalX,
/// principalY) when both are >= 0, else the image centre. Throws Error on a
/// non-positive size, a field of view outside (1, 179) degrees, or a
/// non-finite value.
Camera cameraFor(int width, int height, double horizontalFovDeg, double focalPx, double principalX = -1.0, double principalY = -1.0);

}  // namespace facetrack::core
