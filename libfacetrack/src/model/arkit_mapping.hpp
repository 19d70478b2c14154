#pragma once
// ICT-FaceKit expression weights -> ARKit-52 (order and rules in facetrack/arkit.hpp).

#include "facetrack/arkit.hpp"

#include <array>
#include <string>
#include <vector>

namespace facetrack::model {

/// For each ARKit blendshape, the native expressions whose mean gives it
/// (one, two for browInnerUp and cheekPuff, none for tongueOut).
struct ArkitMapping {
    std::array<std::vector<int>, kArkitBlendshapeCount> sources;
};

/// Throws Error when a native name that an ARKit blendshape needs is missing.
ArkitMapping makeArkitMapping(const std::vector<std::string>& nativeNames);

std::array<float, kArkitBlendshapeCount> toArkit(const ArkitMapping& mapping, const std::vector<float>& native);

}  // namespace facetrack::model
