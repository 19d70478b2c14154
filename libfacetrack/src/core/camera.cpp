#include "core/camera.hpp"

#include "core/math.hpp"

#include "facetrack/error.hpp"

#include <cmath>
#include <string>

namespace facetrack::core {

Camera cameraFor(int width, int height, double horizontalFovDeg, double focalPx, double principalX, double principalY) {
    if (width <= 0 || height <= 0) throw Error("camera: the frame has no pixels");
    if (!std::isfinite(focalPx) || !std::isfinite(principalX) || !std::isfinite(principalY)) {
        throw Error("camera: focal length and principal point must be finite numbers");
    }
    Camera c;
    if (focalPx > 0.0) {
        c.fx = focalPx;
    } else {
        if (!(horizontalFovDeg > 1.0 && horizontalFovDeg < 179.0)) {
            throw Error("camera: horizontal field of view " + std::to_string(horizontalFovDeg) + " deg is outside (1, 179)");
        }
        c.fx = 0.5 * width / std::tan(0.5 * horizontalFovDeg * core::kRadiansPerDegree);
    }
    c.fy = c.fx;
    // Pixel centres are integers (geometry.hpp), so the image centre is at (w - 1) / 2.
    const bool given = principalX >= 0.0 && principalY >= 0.0;
    c.cx = given ? principalX : 0.5 * (width - 1);
    c.cy = given ? principalY : 0.5 * (height - 1);
    return c;
}

}  // namespace facetrack::core
