#pragma once
// Reads iBUG .pts landmark files (300-W): 1-based pixel coordinates on disk,
// 0-based in memory (facetrack's convention, see geometry.hpp).

#include "core/shape2d.hpp"

#include <string>

namespace facetrack::core {

/// Throws Error naming the file when it is missing or malformed.
Shape2 readPts(const std::string& path);

}  // namespace facetrack::core
