#pragma once
// Constants every stage uses.

namespace facetrack::core {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kRadiansPerDegree = kPi / 180.0;

}  // namespace facetrack::core
