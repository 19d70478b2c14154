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

/// The per-frame estimates of one face. With temporal filtering on,
/// FaceResult's own fields are filtered and `raw` holds them unfiltered.
struct FaceEstimates {
    std::optional<Landmarks68> landmarks;
    std::optional<HeadPose> pose;
    std::optional<ExpressionResult> expression;
};

struct FaceResult {
    int id = 0;               ///< stable while the face is followed; a face found again gets a new id
    bool tracked = false;     ///< true when followed from the previous frame, false when freshly detected
    /// 0..1: 1 - fit_residual / TrackerConfig::max_fit_residual once fitted;
    /// the detector's score when the landmarks stage is not available.
    float confidence = 0.f;
    Box box;                  ///< the landmarks' bounding box; the detector's box when there are no landmarks
    std::optional<Landmarks68> landmarks;
    std::optional<HeadPose> pose;
    std::optional<ExpressionResult> expression;
    std::optional<GazeResult> gaze;
    /// RMS distance between the landmarks and the fitted face's projection, in
    /// outer-eye-corner distances (the fit's confidence signal; lower is better).
    std::optional<float> fit_residual;
    /// Identity coefficients of the fitted face (FaceModel::vertices); empty
    /// before calibration, i.e. the mean face.
    std::vector<float> identity;
    bool identity_calibrated = false;
    FaceEstimates raw;        ///< landmarks, pose and expression before temporal filtering
};

/// The pinhole camera the fit assumed (TrackerConfig::camera): a camera-frame
/// point (x, y, z) mm projects to (fx x / z + cx, fy y / z + cy) pixels.
struct CameraIntrinsics {
    float fx = 0.f, fy = 0.f;
    float cx = 0.f, cy = 0.f;
};

/// Wall-clock time one stage took on this frame.
struct StageTiming {
    std::string stage;  ///< "detect", "landmarks", "fit", ...
    double ms = 0.0;
};

struct FrameResult {
    std::vector<FaceResult> faces;     ///< empty: no face
    std::vector<StageTiming> timings;  ///< in pipeline order, only stages that ran
    CameraIntrinsics camera;
};

}  // namespace facetrack
