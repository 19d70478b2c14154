#pragma once
// What a captured neutral leaves alone, for Tracker::calibrateNeutral and the
// guided capture alike: the eyes' look directions (a relaxed face may look
// anywhere).

#include <string_view>

namespace facetrack::calibration {

inline bool keepsItsNeutral(std::string_view arkitName) { return arkitName.rfind("eyeLook", 0) == 0; }

}  // namespace facetrack::calibration
