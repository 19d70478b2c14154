// The user's calibration as data (facetrack/calibration.hpp): its checks, its
// JSON profile and the guided capture that measures it.

#include "facetrack/calibration.hpp"

#include "calibration/neutral.hpp"
#include "facetrack/error.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace facetrack {

namespace {

using Json = nlohmann::ordered_json;

constexpr const char* kFormat = "facetrack-calibration";
constexpr int kVersion = 1;
constexpr float kMaxGain = 10.f;
// Identity coefficients are in standard deviations of the model's identity modes: a face this far
// from the mean is no face, and the fit would not stay finite on it.
constexpr float kMaxIdentity = 10.f;
// A prompted shape must rise this far above its neutral for the capture to
// take its full value: less is a user who did not make the expression, or a
// shape no stage estimates.
constexpr float kMinRange = 0.1f;
constexpr double kFullPercentile = 0.9;

/// The double whose shortest decimal text is the shortest text of `f`: JSON
/// then shows 0.1 rather than 0.100000001, and reads back as the same float.
double shortest(float f) {
    char text[32];
    const auto end = std::to_chars(text, text + sizeof text, f).ptr;
    return std::strtod(std::string(text, end).c_str(), nullptr);
}

float number(const Json& value, const std::string& where) {
    if (!value.is_number()) throw Error("calibration: " + where + " must be a number");
    return static_cast<float>(value.get<double>());
}

std::vector<float> numbers(const Json& value, const std::string& where) {
    if (!value.is_array()) throw Error("calibration: " + where + " must be an array of numbers");
    std::vector<float> out;
    for (std::size_t i = 0; i < value.size(); ++i) out.push_back(number(value[i], where + "[" + std::to_string(i) + "]"));
    return out;
}

Json numbersJson(const std::vector<float>& values) {
    Json out = Json::array();
    for (float v : values) out.push_back(shortest(v));
    return out;
}

std::size_t promptIndex(const std::string& name) {
    const auto& prompts = calibrationPrompts();
    for (std::size_t i = 0; i < prompts.size(); ++i)
        if (prompts[i].name == name) return i;
    std::string known;
    for (const auto& p : prompts) known += (known.empty() ? "" : ", ") + p.name;
    throw Error("calibration: unknown prompt '" + name + "' (" + known + ")");
}

}  // namespace

void validate(const Calibration& calibration) {
    const auto& names = arkitNames();
    for (std::size_t k = 0; k < names.size(); ++k) {
        const ShapeCalibration& s = calibration.shapes[k];
        const std::string name(names[k]);
        if (!(s.neutral >= 0.f && s.neutral < 1.f)) throw Error("calibration: " + name + " neutral must be in [0, 1)");
        if (!(s.full > s.neutral && s.full <= 1.f)) throw Error("calibration: " + name + " full must be in (neutral, 1]");
        if (!(s.gain > 0.f && s.gain <= kMaxGain)) throw Error("calibration: " + name + " gain must be in (0, 10]");
        if (!(s.dead_zone >= 0.f && s.dead_zone < 1.f)) throw Error("calibration: " + name + " dead_zone must be in [0, 1)");
    }
    for (float w : calibration.native_neutral)
        if (!(w >= 0.f && w < 1.f)) throw Error("calibration: native_neutral values must be in [0, 1)");
    for (float c : calibration.identity)
        if (!(std::abs(c) <= kMaxIdentity)) throw Error("calibration: identity values must be within +-10 (standard deviations)");
}

float calibrated(const ShapeCalibration& shape, float w) {
    float r = std::clamp((w - shape.neutral) / (shape.full - shape.neutral), 0.f, 1.f);
    r = r <= shape.dead_zone ? 0.f : (r - shape.dead_zone) / (1.f - shape.dead_zone);
    return std::min(shape.gain * r, 1.f);
}

std::string toJson(const Calibration& calibration) {
    validate(calibration);
    Json shapes = Json::object();
    const ShapeCalibration defaults;
    for (std::size_t k = 0; k < calibration.shapes.size(); ++k) {
        const ShapeCalibration& s = calibration.shapes[k];
        if (s == defaults) continue;
        shapes[std::string(arkitNames()[k])] = {
            {"neutral", shortest(s.neutral)}, {"full", shortest(s.full)}, {"gain", shortest(s.gain)}, {"dead_zone", shortest(s.dead_zone)}};
    }
    const Json out = {{"format", kFormat},
                      {"version", kVersion},
                      {"shapes", shapes},
                      {"native_neutral", numbersJson(calibration.native_neutral)},
                      {"identity", numbersJson(calibration.identity)}};
    return out.dump(1) + "\n";
}

Calibration calibrationFromJson(const std::string& text) {
    Json in;
    try {
        in = Json::parse(text);
    } catch (const nlohmann::json::exception& e) {
        throw Error(std::string("calibration: not valid JSON (") + e.what() + ")");
    }
    if (!in.is_object() || !in.contains("format") || in["format"] != kFormat) {
        throw Error(std::string("calibration: not a ") + kFormat + " file");
    }
    if (!in.contains("version") || in["version"] != kVersion) {
        throw Error("calibration: version " + (in.contains("version") ? in["version"].dump() : "missing") + " (this build reads " +
                    std::to_string(kVersion) + ")");
    }
    Calibration out;
    for (const auto& [key, value] : in.items()) {
        if (key == "format" || key == "version") continue;
        if (key == "native_neutral") {
            out.native_neutral = numbers(value, key);
        } else if (key == "identity") {
            out.identity = numbers(value, key);
        } else if (key == "shapes") {
            if (!value.is_object()) throw Error("calibration: shapes must be an object");
            for (const auto& [name, fields] : value.items()) {
                const int k = arkitIndex(name);
                if (k < 0) throw Error("calibration: unknown shape '" + name + "'");
                if (!fields.is_object()) throw Error("calibration: shape " + name + " must be an object");
                ShapeCalibration& s = out.shapes[static_cast<std::size_t>(k)];
                for (const auto& [field, v] : fields.items()) {
                    const std::string where = name + "." + field;
                    if (field == "neutral") {
                        s.neutral = number(v, where);
                    } else if (field == "full") {
                        s.full = number(v, where);
                    } else if (field == "gain") {
                        s.gain = number(v, where);
                    } else if (field == "dead_zone") {
                        s.dead_zone = number(v, where);
                    } else {
                        throw Error("calibration: unknown field '" + where + "' (neutral, full, gain, dead_zone)");
                    }
                }
            }
        } else {
            throw Error("calibration: unknown field '" + key + "'");
        }
    }
    validate(out);
    return out;
}

void saveCalibration(const Calibration& calibration, const std::string& path) {
    const std::string text = toJson(calibration);
    const std::filesystem::path file(path);
    std::error_code ec;
    if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path(), ec);
    std::ofstream out(path, std::ios::binary);
    out << text;
    out.flush();
    if (!out) throw Error("cannot write the calibration profile '" + path + "'");
}

Calibration loadCalibration(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error("cannot read the calibration profile '" + path + "'");
    std::ostringstream text;
    text << in.rdbuf();
    try {
        return calibrationFromJson(text.str());
    } catch (const Error& e) {
        throw Error(path + ": " + e.what());
    }
}

std::string defaultProfilePath() {
    const char* config = std::getenv("XDG_CONFIG_HOME");
    if (config && *config) return std::string(config) + "/facetrack/profile.json";
    const char* home = std::getenv("HOME");
    return std::string(home && *home ? home : ".") + "/.config/facetrack/profile.json";
}

const std::vector<CalibrationPrompt>& calibrationPrompts() {
    static const std::vector<CalibrationPrompt> prompts = {
        {"neutral", "Relax your face and look at the camera", {}},
        {"smile", "Smile as wide as you can", {"mouthSmileLeft", "mouthSmileRight"}},
        {"open_mouth", "Open your mouth wide", {"jawOpen"}},
        {"pucker", "Kiss: push your lips forward", {"mouthPucker"}},
        {"funnel", "Round your lips as in a long \"oh\"", {"mouthFunnel"}},
        {"brows_up", "Raise your eyebrows", {"browInnerUp", "browOuterUpLeft", "browOuterUpRight"}},
        {"brows_down", "Pull your eyebrows down", {"browDownLeft", "browDownRight"}},
        {"frown", "Pull the corners of your mouth down", {"mouthFrownLeft", "mouthFrownRight"}},
        {"press", "Press your lips together", {"mouthPressLeft", "mouthPressRight"}},
        {"mouth_left", "Pull your mouth to your left", {"mouthLeft"}},
        {"mouth_right", "Pull your mouth to your right", {"mouthRight"}},
        {"squint", "Squint", {"eyeSquintLeft", "eyeSquintRight", "cheekSquintLeft", "cheekSquintRight"}},
        {"sneer", "Wrinkle your nose", {"noseSneerLeft", "noseSneerRight"}},
        {"cheek_puff", "Puff your cheeks", {"cheekPuff"}},
    };
    return prompts;
}

CalibrationCapture::CalibrationCapture(Calibration base) : base_(std::move(base)), frames_(calibrationPrompts().size()) { validate(base_); }

void CalibrationCapture::add(const std::string& prompt, const ExpressionResult& weights) {
    frames_[promptIndex(prompt)].push_back(weights);
}

int CalibrationCapture::frames(const std::string& prompt) const { return static_cast<int>(frames_[promptIndex(prompt)].size()); }

Calibration CalibrationCapture::result() const {
    const auto& neutral = frames_[promptIndex("neutral")];
    if (neutral.empty()) throw Error("calibration: no frame of the neutral face was captured");
    Calibration out = base_;
    const auto& names = arkitNames();
    std::array<double, kArkitBlendshapeCount> mean{};
    for (const auto& frame : neutral)
        for (std::size_t k = 0; k < mean.size(); ++k) mean[k] += frame.arkit[k];
    for (std::size_t k = 0; k < mean.size(); ++k) {
        if (calibration::keepsItsNeutral(names[k])) continue;
        ShapeCalibration& s = out.shapes[k];
        s.neutral = std::min(static_cast<float>(mean[k] / static_cast<double>(neutral.size())), 1.f - kMinRange);
        s.full = 1.f;
    }
    const std::size_t nativeCount = neutral.front().native.size();
    out.native_neutral.assign(nativeCount, 0.f);
    for (const auto& frame : neutral) {
        if (frame.native.size() != nativeCount) throw Error("calibration: the captured frames differ in their native weight count");
        for (std::size_t k = 0; k < nativeCount; ++k) out.native_neutral[k] += frame.native[k] / static_cast<float>(neutral.size());
    }
    for (auto& w : out.native_neutral) w = std::min(w, 1.f - kMinRange);

    const auto& prompts = calibrationPrompts();
    std::vector<float> values;
    for (std::size_t p = 0; p < prompts.size(); ++p) {
        if (frames_[p].empty()) continue;
        for (const auto& shape : prompts[p].shapes) {
            const auto k = static_cast<std::size_t>(arkitIndex(shape));
            values.clear();
            for (const auto& frame : frames_[p]) values.push_back(frame.arkit[k]);
            const auto at = values.begin() + static_cast<std::ptrdiff_t>(kFullPercentile * static_cast<double>(values.size() - 1));
            std::nth_element(values.begin(), at, values.end());
            ShapeCalibration& s = out.shapes[k];
            if (*at >= s.neutral + kMinRange) s.full = std::min(*at, 1.f);
        }
    }
    validate(out);
    return out;
}

}  // namespace facetrack
