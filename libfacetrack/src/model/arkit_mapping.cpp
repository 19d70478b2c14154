#include "model/arkit_mapping.hpp"

#include "facetrack/error.hpp"

#include <algorithm>

namespace facetrack {

const std::array<std::string_view, kArkitBlendshapeCount>& arkitNames() {
    static const std::array<std::string_view, kArkitBlendshapeCount> names = {
        "eyeBlinkLeft",      "eyeLookDownLeft",    "eyeLookInLeft",       "eyeLookOutLeft",   "eyeLookUpLeft",     "eyeSquintLeft",
        "eyeWideLeft",       "eyeBlinkRight",      "eyeLookDownRight",    "eyeLookInRight",   "eyeLookOutRight",   "eyeLookUpRight",
        "eyeSquintRight",    "eyeWideRight",       "jawForward",          "jawLeft",          "jawRight",          "jawOpen",
        "mouthClose",        "mouthFunnel",        "mouthPucker",         "mouthLeft",        "mouthRight",        "mouthSmileLeft",
        "mouthSmileRight",   "mouthFrownLeft",     "mouthFrownRight",     "mouthDimpleLeft",  "mouthDimpleRight",  "mouthStretchLeft",
        "mouthStretchRight", "mouthRollLower",     "mouthRollUpper",      "mouthShrugLower",  "mouthShrugUpper",   "mouthPressLeft",
        "mouthPressRight",   "mouthLowerDownLeft", "mouthLowerDownRight", "mouthUpperUpLeft", "mouthUpperUpRight", "browDownLeft",
        "browDownRight",     "browInnerUp",        "browOuterUpLeft",     "browOuterUpRight", "cheekPuff",         "cheekSquintLeft",
        "cheekSquintRight",  "noseSneerLeft",      "noseSneerRight",      "tongueOut",
    };
    return names;
}

int arkitIndex(std::string_view name) {
    const auto& names = arkitNames();
    const auto it = std::find(names.begin(), names.end(), name);
    return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

namespace model {

namespace {
bool endsWith(std::string_view s, std::string_view suffix) {
    return s.size() >= suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

/// Candidate ICT names for an ARKit blendshape: the same name ("jawLeft",
/// "mouthRight"), else the side suffix form ("eyeBlinkLeft" -> "eyeBlink_L").
std::vector<std::string> candidateNames(std::string_view arkit) {
    std::vector<std::string> names = {std::string(arkit)};
    if (endsWith(arkit, "Left")) names.push_back(std::string(arkit.substr(0, arkit.size() - 4)) + "_L");
    if (endsWith(arkit, "Right")) names.push_back(std::string(arkit.substr(0, arkit.size() - 5)) + "_R");
    return names;
}

int indexOf(const std::vector<std::string>& names, const std::string& name) {
    const auto it = std::find(names.begin(), names.end(), name);
    return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}
}  // namespace

ArkitMapping makeArkitMapping(const std::vector<std::string>& nativeNames) {
    ArkitMapping mapping;
    const auto& names = arkitNames();
    for (int k = 0; k < kArkitBlendshapeCount; ++k) {
        const std::string_view name = names[k];
        if (name == "tongueOut") continue;  // not in the model
        if (name == "browInnerUp" || name == "cheekPuff") {
            for (const char* side : {"_L", "_R"}) {
                const int i = indexOf(nativeNames, std::string(name) + side);
                if (i < 0) throw Error("face model has no expression '" + std::string(name) + side + "'");
                mapping.sources[k].push_back(i);
            }
            continue;
        }
        for (const auto& candidate : candidateNames(name)) {
            const int i = indexOf(nativeNames, candidate);
            if (i >= 0) {
                mapping.sources[k] = {i};
                break;
            }
        }
        if (mapping.sources[k].empty()) {
            throw Error("face model has no expression for ARKit '" + std::string(name) + "'");
        }
    }
    return mapping;
}

std::array<float, kArkitBlendshapeCount> toArkit(const ArkitMapping& mapping, const std::vector<float>& native) {
    std::array<float, kArkitBlendshapeCount> arkit{};
    for (int k = 0; k < kArkitBlendshapeCount; ++k) {
        const auto& sources = mapping.sources[k];
        if (sources.empty()) continue;
        float sum = 0.f;
        for (int i : sources) sum += native.at(static_cast<std::size_t>(i));
        arkit[k] = sum / static_cast<float>(sources.size());
    }
    return arkit;
}

}  // namespace model
}  // namespace facetrack
