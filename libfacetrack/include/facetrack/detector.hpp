#pragma once
/// \file
/// Face detection: boxes and scores for the faces in a frame.
///
/// The default detector is YuNet (2022mar, through OpenCV's FaceDetectorYN).
/// Its model file is not shipped; it is looked for in this order:
///   1. DetectorConfig::yunet_model;
///   2. the FACETRACK_YUNET_MODEL environment variable;
///   3. face_detection_yunet_2022mar.onnx in the model directory (modelDirectory());
///   4. ../shared/models/yunet/ from the working directory and from the source tree.
/// When none exists, detection falls back to OpenCV's Haar cascade from
/// Debian's opencv-data, and a log line says so.

#include "facetrack/geometry.hpp"
#include "facetrack/image.hpp"

#include <memory>
#include <string>
#include <vector>

namespace facetrack {

struct Detection {
    Box box;            ///< image pixels, 0-based
    float score = 0.f;  ///< 0..1
};

enum class DetectorKind {
    Auto,     ///< YuNet when its model is found, else the cascade
    YuNet,    ///< YuNet or an error
    Cascade,  ///< OpenCV Haar cascade
};

struct DetectorConfig {
    DetectorKind kind = DetectorKind::Auto;
    std::string yunet_model;   ///< empty: search as described above
    std::string cascade_file;  ///< empty: opencv-data's haarcascade_frontalface_alt2.xml
    /// Detections scoring below this are dropped. YuNet detections under 0.9
    /// must also be confirmed at a second, smaller input size, which rejects
    /// its false alarms on featureless frames (docs/detector.md).
    float min_score = 0.5f;
    int detect_width = 320;  ///< frames wider than this are downscaled to it before detection
    int max_faces = 8;       ///< keep at most this many, highest score first
};

/// One detector instance is used by one thread at a time (OpenCV's networks
/// keep per-call state); create one per Tracker.
class FaceDetector {
public:
    virtual ~FaceDetector() = default;
    /// Faces in the frame, highest score first. Throws Error on an invalid view.
    virtual std::vector<Detection> detect(const ImageView& frame) = 0;
    /// "yunet" or "cascade".
    virtual std::string kind() const = 0;
    /// The model file in use.
    virtual std::string modelPath() const = 0;
};

/// Creates the configured detector and logs which one is in use. Throws
/// facetrack::Error when the requested detector cannot be created.
std::unique_ptr<FaceDetector> createFaceDetector(const DetectorConfig& config = {});

/// Where YuNet's model would be loaded from under this config, or "" when it
/// is not found.
std::string findYuNetModel(const DetectorConfig& config = {});

}  // namespace facetrack
