#pragma once
/// \file
/// One user's calibration, as plain data: what their relaxed face reads, how
/// far each of their full expressions reaches, and the shape of their face. A
/// Tracker applies one (Tracker::setCalibration) and produces one
/// (Tracker::calibration); saved as JSON (a profile file) it reads back exactly.
///
/// Each ARKit weight w is reported as
///     r  = clamp((w - w0) / (w1 - w0), 0, 1)     w0 = neutral, w1 = full
///     r' = r <= d ? 0 : (r - d) / (1 - d)         d  = dead_zone
///     w' = min(g r', 1)                           g  = gain
/// so the relaxed face reads 0, the user's full expression reaches 1, twitches
/// below the dead zone read 0 and the gain makes a shape livelier. The defaults
/// (0, 1, 1, 0) leave w as it is.
///
/// Guided capture (CalibrationCapture): the user holds a relaxed face, then a
/// few prompted expressions (calibrationPrompts()); the capture takes the
/// neutral from the first and each prompted shape's full value from the others.

#include "facetrack/arkit.hpp"
#include "facetrack/result.hpp"

#include <array>
#include <string>
#include <vector>

namespace facetrack {

/// How one ARKit weight is reported (see the file comment).
struct ShapeCalibration {
    float neutral = 0.f;    ///< w0: the weight on the user's relaxed face, in [0, 1)
    float full = 1.f;       ///< w1: the weight of the user's full expression, in (neutral, 1]
    float gain = 1.f;       ///< g, in (0, 10]
    float dead_zone = 0.f;  ///< d, in [0, 1)
    bool operator==(const ShapeCalibration& o) const {
        return neutral == o.neutral && full == o.full && gain == o.gain && dead_zone == o.dead_zone;
    }
    bool operator!=(const ShapeCalibration& o) const { return !(*this == o); }
};

struct Calibration {
    /// One per ARKit shape, in arkitNames() order.
    std::array<ShapeCalibration, kArkitBlendshapeCount> shapes{};
    /// The face model's own weights on the relaxed face (FaceModel::expressionNames()
    /// order; empty: all 0). Each native weight is reported with its own neutral
    /// and the full value, gain and dead zone of the ARKit shape it drives.
    std::vector<float> native_neutral;
    /// The user's identity coefficients (FaceResult::identity; standard deviations
    /// of the model's identity modes, each within +-10). Empty: the Tracker
    /// estimates them from the first frames (TrackerConfig::calibration_frames).
    std::vector<float> identity;

    bool operator==(const Calibration& o) const {
        return shapes == o.shapes && native_neutral == o.native_neutral && identity == o.identity;
    }
    bool operator!=(const Calibration& o) const { return !(*this == o); }
};

/// Throws Error naming the first value out of range (or not finite).
void validate(const Calibration& calibration);

/// w' for a weight w (see the file comment).
float calibrated(const ShapeCalibration& shape, float w);

/// The JSON profile: {"format": "facetrack-calibration", "version": 1,
/// "shapes": {"browDownLeft": {"neutral": .., "full": .., "gain": .., "dead_zone": ..}, ...},
/// "native_neutral": [...], "identity": [...]}. Shapes at their defaults are
/// left out; every number is the shortest text that reads back as the same float.
std::string toJson(const Calibration& calibration);
/// Reads toJson's text (a shape or field left out keeps its default). Throws
/// Error on malformed or truncated JSON, another format or version, an unknown
/// shape or field, or a value validate() refuses.
Calibration calibrationFromJson(const std::string& text);

/// toJson into `path` (its folder created when missing); throws Error when it cannot be written.
void saveCalibration(const Calibration& calibration, const std::string& path);
/// calibrationFromJson of the file at `path`; the Error names the file.
Calibration loadCalibration(const std::string& path);
/// Where a user's profile lives by default: $XDG_CONFIG_HOME/facetrack/profile.json,
/// or ~/.config/facetrack/profile.json when XDG_CONFIG_HOME is not set.
std::string defaultProfilePath();

/// One step of a guided capture.
struct CalibrationPrompt {
    std::string name;                 ///< "neutral", "smile", ... (the labels of data/expression_labels.csv)
    std::string instruction;          ///< what to ask of the user
    std::vector<std::string> shapes;  ///< the ARKit shapes whose full value it measures; empty for "neutral"
};

/// "neutral" first, then the expressions in the order a user is asked for them.
const std::vector<CalibrationPrompt>& calibrationPrompts();

/// Collects a guided capture. Feed it the weights a Tracker reports without a
/// calibration (Tracker::setCalibration({}) before the capture; the identity is
/// kept), each with the prompt the user was holding.
class CalibrationCapture {
public:
    /// Starts from `base`: what the capture does not measure is kept from it.
    explicit CalibrationCapture(Calibration base = {});
    /// One frame's weights while the user holds `prompt` (a calibrationPrompts() name;
    /// throws Error for another).
    void add(const std::string& prompt, const ExpressionResult& weights);
    /// Frames added for `prompt` so far.
    int frames(const std::string& prompt) const;
    /// The calibration: each shape's neutral is its mean over the "neutral"
    /// frames (the eyes' look directions keep theirs: a relaxed face may look
    /// anywhere); each prompted shape's full value is the 90th percentile of
    /// its prompt's frames, kept only when that is at least 0.1 above its
    /// neutral (the user made the expression, and the shape is estimated).
    /// Throws Error when no neutral frame was added.
    Calibration result() const;

private:
    Calibration base_;
    std::vector<std::vector<ExpressionResult>> frames_;  // per prompt, calibrationPrompts() order
};

}  // namespace facetrack
