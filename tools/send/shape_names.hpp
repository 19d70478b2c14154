#pragma once
// The names avatar apps give the ARKit shapes, and the VRM 0.x presets derived
// from them for avatars without the 52 "Perfect Sync" shapes (docs/protocols.md).

#include "facetrack/arkit.hpp"

#include <array>
#include <string>
#include <string_view>

namespace facetrack::send {

/// Perfect Sync's UpperCamelCase name of an ARKit name: "jawOpen" -> "JawOpen".
std::string perfectSyncName(std::string_view arkit);

/// iFacialMocap's name: "Left"/"Right" become "_L"/"_R" ("eyeBlinkLeft" ->
/// "eyeBlink_L"), except jawLeft, jawRight, mouthLeft and mouthRight, which
/// are directions, not sides, and keep the whole word.
std::string iFacialMocapName(std::string_view arkit);

/// VRM 0.x blend shape presets, each a clamped combination of ARKit weights.
struct VrmPreset {
    std::string_view name;
    float (*weight)(const std::array<float, kArkitBlendshapeCount>& arkit);
};
const std::array<VrmPreset, 14>& vrmPresets();

}  // namespace facetrack::send
