#pragma once
// JSON pieces shared by the CLI's commands (nlohmann's ordered_json keeps
// fields in the documented order).

#include "facetrack/geometry.hpp"

#include <nlohmann/json.hpp>

#include <cmath>

namespace facetrack::cli {

using Json = nlohmann::ordered_json;

/// A number rounded to 1/100 (pixels, scores, ms) for readable output.
inline double round2(double v) { return std::round(v * 100.0) / 100.0; }

inline Json boxJson(const Box& b) { return {round2(b.x0), round2(b.y0), round2(b.x1), round2(b.y1)}; }

inline Json landmarksJson(const Landmarks68& points) {
    Json out = Json::array();
    for (const auto& p : points) out.push_back({round2(p.x), round2(p.y)});
    return out;
}

}  // namespace facetrack::cli
