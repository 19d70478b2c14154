#include "fit/camera.hpp"

#include "facetrack/error.hpp"

#include <cmath>
#include <string>

namespace facetrack::fit {

Camera cameraFor(int width, int height, double horizontalFovDeg, double focalPx) {
    if (width <= 0 || height <= 0) throw Error("camera: the frame has no pixels");
    Camera c;
    if (focalPx > 0.0) {
        c.fx = focalPx;
    } else {
        if (!(horizontalFovDeg > 1.0 && horizontalFovDeg < 179.0)) {
            throw Error("camera: horizontal field of view " + std::to_string(horizontalFovDeg) +
                        " deg is outside (1, 179)");
        }
        c.fx = 0.5 * width / std::tan(0.5 * horizontalFovDeg * 3.14159265358979323846 / 180.0);
    }
    c.fy = c.fx;
    // Pixel centres are integers (geometry.hpp), so the image centre is at (w - 1) / 2.
    c.cx = 0.5 * (width - 1);
    c.cy = 0.5 * (height - 1);
    return c;
}

}  // namespace facetrack::fit
