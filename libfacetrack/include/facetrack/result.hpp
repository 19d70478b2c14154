#pragma once
/// \file
/// What the Tracker returns for a frame: plain values that own their data
/// (copy them, keep them, hand them to another thread).
///
/// A stage that is not available, or did not run for a face, leaves its field
/// empty (std::nullopt): facetrack never fills a field with made-up values.
/// Tracker::stages() tells which stages this build and configuration have.
///
/// Camera frame (for pose and gaze): OpenCV's pinhole convention. Origin at
/// the camera centre, +x to the right of the image, +y down the image, +z
/// forward into the scene; millimetres.
///
/// Model frame (the face model's own): origin between the ears, +x towards
/// the subject's left, +y up, +z out of the face; millimetres.
///
/// OpenGL eye frame (HeadPose::gl_model_view): +x right, +y up, +z towards
/// the viewer, i.e. the camera frame with y and z negated.

#include "facetrack/arkit.hpp"
#include "facetrack/geometry.hpp"

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace facetrack {

/// Rigid head pose: x_camera = rotation * x_model + translation_mm.
///
/// Worked example: a face looking straight into the camera 500 mm in front of
/// it has rotation (w, x, y, z) = (0, 1, 0, 0) (a half turn about x: model +y
/// up becomes camera -y, up the image; model +z out of the face becomes -z,
/// towards the camera), translation_mm (0, 0, 500), and
///   camera_from_model = | 1  0  0   0 |      gl_model_view = | 1 0 0    0 |
///                       | 0 -1  0   0 |                      | 0 1 0    0 |
///                       | 0  0 -1 500 |                      | 0 0 1 -500 |
///                       | 0  0  0   1 |                      | 0 0 0    1 |
/// so in OpenGL the same face needs no rotation and sits 500 mm down the -z
/// axis: load gl_model_view as the model-view matrix of the face model's mesh
/// (FaceModel::vertices, mm) and draw it with a projection made from
/// FrameResult::camera to overlay the video exactly.
struct HeadPose {
    Quaternion rotation;
    /// (pitch, yaw, roll) in degrees, relative to a face looking straight at
    /// the camera: pitch > 0 chin down, yaw > 0 the face turns to the image's
    /// right (subject's left), roll > 0 the head tilts clockwise in the image.
    /// Applied as yaw, then pitch, then roll.
    Vec3 euler_deg;
    Vec3 translation_mm;
    /// [R t; 0 1] in the camera frame, column-major (Mat4): x_camera = M x_model.
    Mat4 camera_from_model{};
    /// The same transform into OpenGL's eye frame: diag(1, -1, -1, 1) camera_from_model.
    Mat4 gl_model_view{};
};

struct ExpressionResult {
    /// ARKit-52 weights in [0, 1], in arkitNames() order.
    std::array<float, kArkitBlendshapeCount> arkit{};
    /// The face model's own expression weights, in FaceModel::expressionNames() order.
    std::vector<float> native;
};

/// One eye's gaze (the gaze stage, docs/gaze.md). Yaw and pitch are in the
/// head's frame: 0, 0 looks straight out of the face.
struct EyeGaze {
    Vec3 direction;         ///< unit vector in the camera frame, from the eyeball centre
    Vec3 direction_head;    ///< the same in the model (head) frame
    float yaw_deg = 0.f;    ///< > 0: towards the subject's left (the image's right for a face looking at the camera)
    float pitch_deg = 0.f;  ///< > 0: up
    float openness = 0.f;   ///< 0 closed .. 1 open (the lid aperture over this face's open-eye aperture)
    Point2 pupil_px;        ///< the iris centre in the frame, pixels
};

struct GazeResult {
    EyeGaze left;   ///< the subject's left eye (landmarks 42-47)
    EyeGaze right;  ///< the subject's right eye (landmarks 36-41)
};

/// The per-frame estimates of one face before temporal filtering. Filled by the
/// filter stage; empty when the filter is off (FaceResult's own fields are
/// then unfiltered).
struct FaceEstimates {
    std::optional<Landmarks68> landmarks;
    std::optional<HeadPose> pose;
    std::optional<ExpressionResult> expression;
};

struct FaceResult {
    int id =
        0;  ///< stable while the face is followed, also when the tracker finds it again near where it was; a face lost and found by a new search gets a new id
    bool tracked = false;  ///< true when followed from the previous frame, false when freshly detected
    /// 0..1: 1 - fit_residual / TrackerConfig::max_fit_residual once fitted;
    /// the detector's score when the landmarks stage is not available.
    float confidence = 0.f;
    /// The bounding box of the unfiltered landmarks (raw.landmarks); the
    /// detector's box when there are no landmarks.
    Box box;
    std::optional<Landmarks68> landmarks;
    std::optional<HeadPose> pose;
    std::optional<ExpressionResult> expression;
    std::optional<GazeResult> gaze;
    /// RMS distance between the landmarks and the fitted face's projection, in
    /// outer-eye-corner distances, or half the landmarks' box size, sqrt(w h),
    /// where that is larger (a face turned far) (the fit's confidence signal; lower is better).
    std::optional<float> fit_residual;
    /// Identity coefficients of the fitted face (FaceModel::vertices); empty
    /// before calibration, i.e. the mean face.
    std::vector<float> identity;
    bool identity_calibrated = false;
    FaceEstimates raw;  ///< landmarks, pose and expression before temporal filtering (see FaceEstimates)
};

/// The pinhole camera the fit assumed (TrackerConfig::camera): a camera-frame
/// point (x, y, z) mm projects to (fx x / z + cx, fy y / z + cy) pixels.
struct CameraIntrinsics {
    float fx = 0.f, fy = 0.f;
    float cx = 0.f, cy = 0.f;
    int width = 0, height = 0;  ///< the frame's size in pixels
};

/// One entry of Tracker::stages(). The same names label FrameResult::timings.
struct StageInfo {
    std::string name;  ///< "detect", "verify", "landmarks", "refine", "fit", "cnn", "gaze", "filter", "calibration"
    bool available = false;
    std::string detail;  ///< what implements it, or why it is not available
};

/// Wall-clock time one stage took on this frame, summed over faces.
struct StageTiming {
    std::string stage;  ///< a name of Tracker::stages(): "detect", "verify", "landmarks", "fit", ...
    double ms = 0.0;
};

/// Everything the Tracker says about one frame. Pass the same FrameResult to
/// Tracker::process frame after frame: its memory is reused, so tracking
/// allocates nothing once the number of faces is steady (docs/architecture.md).
struct FrameResult {
    std::vector<FaceResult> faces;     ///< empty: no face
    std::vector<StageTiming> timings;  ///< in Tracker::stages() order, only stages that ran
    CameraIntrinsics camera;
};

}  // namespace facetrack
