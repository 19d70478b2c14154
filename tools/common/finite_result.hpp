#pragma once
// The robustness check of docs/robustness.md, shared by the tests and the fuzz
// targets: every number a face result carries is finite (the fit's residual
// may be +inf, its documented "no usable fit", never NaN) and every ARKit
// weight is in [0, 1].

#include "facetrack/result.hpp"

#include <cmath>
#include <string>

namespace facetrack::tools {

/// What is not finite in `f`, or "" when everything is.
inline std::string firstNonFinite(const FaceResult& f) {
    const auto finite = [](auto... v) { return (std::isfinite(v) && ...); };
    const auto point = [&](const Point2& p) { return finite(p.x, p.y); };
    const auto vec = [&](const Vec3& v) { return finite(v.x, v.y, v.z); };
    if (!finite(f.confidence, f.box.x0, f.box.y0, f.box.x1, f.box.y1)) return "the box or the confidence";
    if (f.landmarks)
        for (const Point2& p : *f.landmarks)
            if (!point(p)) return "a landmark";
    if (f.pose) {
        const Quaternion& q = f.pose->rotation;
        if (!finite(q.w, q.x, q.y, q.z) || !vec(f.pose->translation_mm) || !vec(f.pose->euler_deg)) return "the head pose";
    }
    if (f.expression)
        for (const float w : f.expression->arkit)
            if (!(w >= 0.f && w <= 1.f)) return "an ARKit weight outside [0, 1]";
    if (f.gaze)
        for (const EyeGaze* e : {&f.gaze->left, &f.gaze->right})
            if (!vec(e->direction) || !vec(e->direction_head) || !finite(e->yaw_deg, e->pitch_deg, e->openness) || !point(e->pupil_px))
                return "a gaze value";
    if (f.fit_residual && std::isnan(*f.fit_residual)) return "the fit residual (NaN)";
    for (const float a : f.identity)
        if (!finite(a)) return "an identity coefficient";
    return "";
}

}  // namespace facetrack::tools
