#pragma once
// Box arithmetic shared by the detector and the tracker.

#include "facetrack/geometry.hpp"

#include <algorithm>

namespace facetrack::core {

/// Intersection over union of two boxes; 0 when they do not overlap.
inline float intersectionOverUnion(const Box& a, const Box& b) {
    const float w = std::min(a.x1, b.x1) - std::max(a.x0, b.x0), h = std::min(a.y1, b.y1) - std::max(a.y0, b.y0);
    if (w <= 0.f || h <= 0.f) return 0.f;
    const float inter = w * h;
    return inter / (a.width() * a.height() + b.width() * b.height() - inter);
}

inline bool contains(const Box& box, float x, float y) { return x >= box.x0 && x <= box.x1 && y >= box.y0 && y <= box.y1; }

}  // namespace facetrack::core
