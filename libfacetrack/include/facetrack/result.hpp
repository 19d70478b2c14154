#pragma once
/// \file
/// What the Tracker returns for a frame.
///
/// A stage that is not built, or did not run for a face, leaves its field
/// empty (std::nullopt): facetrack never fills a field with made-up values.
/// Tracker::availableStages() tells which stages this build has.
///
/// Camera frame (for pose and gaze): OpenCV's pinhole convention. Origin at
/// the camera centre, +x to the right of the image, +y down the image, +z
/// forward into the scene; millimetres.
///
/// Model frame (the face model's own): origin between the ears, +x towards
/// the subject's left, +y up, +z out of the face.

#include "facetrack/arkit.hpp"
#include "facetrack/geometry.hpp"

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace facetrack {

/// Rigid head pose: x_camera = rotation * x_model + translation.
struct HeadPose {
    Quaternion rotation;
    /// (pitch, yaw, roll) in degrees, relative to a face looking straight at
    /// the camera: pitch > 0 chin down, yaw > 0 the face turns to the image's
    /// right (subject's left), roll > 0 the head tilts clockwise in the image.
    /// Applied as yaw, then pitch, then roll.
    Vec3 euler_deg;
    Vec3 translation_mm;
};

struct ExpressionResult {
    /// ARKit-52 weights in [0, 1], in arkitNames() order.
    std::array<float, kArkitBlendshapeCount> arkit{};
    /// The face model's own expression weights, in FaceModel::expressionNames() order.
    std::vector<float> native;
};

struct EyeGaze {
    Vec3 direction;       ///< unit vector in the camera frame, from the eyeball centre
    float yaw_deg = 0.f;  ///< > 0: looking to the image's right
    float pitch_deg = 0.f;///< > 0: looking up
    float openness = 0.f; ///< 0 closed .. 1 fully open
};

struct GazeResult {
    EyeGaze left;   ///< the subject's left eye (landmarks 42-47)
    EyeGaze right;  ///< the subject's right eye (landmarks 36-41)
};

struct FaceResult {
    bool tracked = false;     ///< true when followed from the previous frame, false when freshly detected
    float confidence = 0.f;   ///< 0..1; from the detector until a later stage refines it
    Box box;                  ///< face box in image pixels
    std::optional<Landmarks68> landmarks;
    std::optional<HeadPose> pose;
    std::optional<ExpressionResult> expression;
    std::optional<GazeResult> gaze;
};

/// Wall-clock time one stage took on this frame.
struct StageTiming {
    std::string stage;  ///< "detect", "landmarks", "fit", ...
    double ms = 0.0;
};

struct FrameResult {
    std::vector<FaceResult> faces;     ///< empty: no face
    std::vector<StageTiming> timings;  ///< in pipeline order, only stages that ran
};

}  // namespace facetrack
