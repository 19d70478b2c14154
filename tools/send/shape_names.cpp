#include "send/shape_names.hpp"

#include <algorithm>
#include <cctype>

namespace facetrack::send {

namespace {
using Weights = std::array<float, kArkitBlendshapeCount>;

float w(const Weights& a, std::string_view name) { return a[static_cast<std::size_t>(arkitIndex(name))]; }
float both(const Weights& a, std::string_view left, std::string_view right) { return 0.5f * (w(a, left) + w(a, right)); }
float unit(float x) { return std::clamp(x, 0.f, 1.f); }

bool endsWith(std::string_view s, std::string_view tail) { return s.size() >= tail.size() && s.substr(s.size() - tail.size()) == tail; }
}  // namespace

std::string perfectSyncName(std::string_view arkit) {
    std::string name(arkit);
    if (!name.empty()) name[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(name[0])));
    return name;
}

std::string iFacialMocapName(std::string_view arkit) {
    if (arkit == "jawLeft" || arkit == "jawRight" || arkit == "mouthLeft" || arkit == "mouthRight") return std::string(arkit);
    if (endsWith(arkit, "Left")) return std::string(arkit.substr(0, arkit.size() - 4)) + "_L";
    if (endsWith(arkit, "Right")) return std::string(arkit.substr(0, arkit.size() - 5)) + "_R";
    return std::string(arkit);
}

// The vowels follow the mouth shapes that make them: A open, I spread, U and O
// rounded (closed and open), E half open and spread. Left/Right are the
// avatar's own sides, like ARKit's: LookLeft is both eyes turned to the
// subject's left (left eye out, right eye in).
const std::array<VrmPreset, 14>& vrmPresets() {
    static const std::array<VrmPreset, 14> presets = {{
        {"Blink_L", [](const Weights& a) { return w(a, "eyeBlinkLeft"); }},
        {"Blink_R", [](const Weights& a) { return w(a, "eyeBlinkRight"); }},
        {"A", [](const Weights& a) { return unit(w(a, "jawOpen") - w(a, "mouthFunnel")); }},
        {"I", [](const Weights& a) { return unit(both(a, "mouthStretchLeft", "mouthStretchRight") - 0.5f * w(a, "jawOpen")); }},
        {"U", [](const Weights& a) { return unit(w(a, "mouthPucker") - 0.5f * w(a, "jawOpen")); }},
        {"E", [](const Weights& a) { return std::min(w(a, "jawOpen"), both(a, "mouthStretchLeft", "mouthStretchRight")); }},
        {"O", [](const Weights& a) { return unit(std::min(w(a, "mouthFunnel"), 2.f * w(a, "jawOpen"))); }},
        {"Joy", [](const Weights& a) { return both(a, "mouthSmileLeft", "mouthSmileRight"); }},
        {"Angry", [](const Weights& a) { return both(a, "browDownLeft", "browDownRight"); }},
        {"Sorrow", [](const Weights& a) { return 0.5f * (w(a, "browInnerUp") + both(a, "mouthFrownLeft", "mouthFrownRight")); }},
        {"LookUp", [](const Weights& a) { return both(a, "eyeLookUpLeft", "eyeLookUpRight"); }},
        {"LookDown", [](const Weights& a) { return both(a, "eyeLookDownLeft", "eyeLookDownRight"); }},
        {"LookLeft", [](const Weights& a) { return both(a, "eyeLookOutLeft", "eyeLookInRight"); }},
        {"LookRight", [](const Weights& a) { return both(a, "eyeLookInLeft", "eyeLookOutRight"); }},
    }};
    return presets;
}

}  // namespace facetrack::send
