#pragma once
/// \file
/// Plain value types shared by the results. Lengths in 3D are millimetres
/// everywhere in the public API; image positions are pixels. Plain values.

#include <array>

namespace facetrack {

/// A point in image pixels: 0-based, (0, 0) is the centre of the top-left pixel.
struct Point2 {
    float x = 0.f;
    float y = 0.f;
};

/// An axis-aligned box in image pixels, corners (x0, y0) top-left and (x1, y1)
/// bottom-right, in the same 0-based convention as Point2.
struct Box {
    float x0 = 0.f;
    float y0 = 0.f;
    float x1 = 0.f;
    float y1 = 0.f;
    float width() const { return x1 - x0; }
    float height() const { return y1 - y0; }
};

struct Vec3 {
    float x = 0.f;
    float y = 0.f;
    float z = 0.f;
};

/// Unit quaternion w + xi + yj + zk.
struct Quaternion {
    float w = 1.f;
    float x = 0.f;
    float y = 0.f;
    float z = 0.f;
};

/// A 4x4 matrix in column-major order (OpenGL's and GLM's layout): the
/// element in row r, column c is at index 4 c + r, so the translation of a
/// rigid transform is at indices 12, 13, 14.
using Mat4 = std::array<float, 16>;

/// The 68 iBUG / Multi-PIE landmarks, in that point order (0-based indices;
/// 36 and 45 are the outer eye corners).
using Landmarks68 = std::array<Point2, 68>;

}  // namespace facetrack
