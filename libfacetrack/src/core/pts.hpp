#pragma once
// Reads and writes iBUG .pts landmark files (300-W): 1-based pixel coordinates on disk,
// 0-based in memory (facetrack's convention, see geometry.hpp).

#include "core/shape2d.hpp"

#include <string>

namespace facetrack::core {

/// Throws Error naming the file when it is missing or malformed.
Shape2 readPts(const std::string& path);

/// Writes `points` as readPts reads them; throws Error when the file cannot be written.
void writePts(const std::string& path, const Shape2& points);

}  // namespace facetrack::core
