#pragma once
/// \file
/// The 52 ARKit blendshapes in facetrack's fixed order.
///
/// The order is Apple's grouping (eyes, jaw, mouth, brows, cheeks, nose,
/// tongue), the same as Live Link Face's CSV columns; docs/api.md lists it.
/// "Left" and "Right" are the subject's own sides, as in ARKit.
/// Mapping from the ICT-FaceKit model: `X_L` -> `XLeft`, `X_R` -> `XRight`;
/// browInnerUp and cheekPuff are the mean of their _L/_R pair; tongueOut is
/// not modelled and is always 0.
///
/// Constant data: safe from any thread.

#include <array>
#include <string_view>

namespace facetrack {

constexpr int kArkitBlendshapeCount = 52;

/// Names in output order; index i of ExpressionResult::arkit is arkitNames()[i].
const std::array<std::string_view, kArkitBlendshapeCount>& arkitNames();

/// Index of an ARKit name, or -1 if it is not one of the 52.
int arkitIndex(std::string_view name);

}  // namespace facetrack
