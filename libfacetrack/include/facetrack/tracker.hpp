#pragma once
/// \file
/// The Tracker wires the stages into one pipeline:
///   frame -> detect (when fewer faces than wanted are followed) -> verify (now and then)
///         -> per face: landmarks -> refine -> fit -> cnn -> gaze -> filter -> calibration -> result
/// docs/architecture.md shows the data flow. Stages not built yet report
/// "not available" and leave their fields of FaceResult empty.
///
/// Ownership and threads: models are immutable and shared (shared_ptr) by any
/// number of Trackers on any threads. A Tracker follows one video stream and
/// is used by one thread at a time; run one Tracker per stream or per thread.

#include "facetrack/calibration.hpp"
#include "facetrack/cnn_model.hpp"
#include "facetrack/detector.hpp"
#include "facetrack/eye_model.hpp"
#include "facetrack/face_model.hpp"
#include "facetrack/image.hpp"
#include "facetrack/landmark_model.hpp"
#include "facetrack/refiner_model.hpp"
#include "facetrack/result.hpp"

#include <memory>
#include <string>
#include <vector>

namespace facetrack {

/// The models a Tracker uses, loaded once and shared (immutable) by any
/// number of Trackers on any threads.
struct Models {
    std::shared_ptr<const FaceModel> face;           ///< required
    std::shared_ptr<const LandmarkModel> landmarks;  ///< null: the landmarks stage is not available
    std::shared_ptr<const EyeModel> eyes;            ///< null: the gaze stage is not available
    std::shared_ptr<const CnnModel> cnn;             ///< null: the cnn stage is not available
    std::shared_ptr<const RefinerModel> refiner;     ///< null: the refine stage is not available

    /// The shipped models from modelDirectory(). A missing landmark, refiner, eye
    /// or CNN model leaves its pointer null (and is logged); any other problem throws Error.
    static Models loadDefault();
};

/// The webcam's pinhole model (square pixels). Focal length: `focal_length_px`
/// when positive, else from the horizontal field of view. Principal point:
/// (principal_x_px, principal_y_px) when both are given (>= 0), else the image
/// centre. docs/fitting.md says how to calibrate it; a wrong focal length
/// biases depth and, a little, pitch and yaw.
struct CameraConfig {
    double horizontal_fov_deg = 60.0;  ///< a typical webcam
    double focal_length_px = 0.0;      ///< at the frame's resolution; 0: use the field of view
    double principal_x_px = -1.0;      ///< at the frame's resolution, 0-based pixel centres; < 0: the image centre
    double principal_y_px = -1.0;
};

/// The 1-euro filter on landmarks, pose and expressions (docs/fitting.md).
/// Speeds are measured in face sizes per second, so one setting suits near
/// and far faces.
struct FilterConfig {
    bool enabled = true;
    double min_cutoff_hz = 1.0;  ///< cutoff at rest: lower = steadier
    /// How fast the cutoff rises with speed: higher = less lag. The landmarks'
    /// cutoff rises with their own speed and, 5x as fast, with the whole face's.
    double beta = 2.0;
    double derivative_cutoff_hz = 1.0;
};

struct TrackerConfig {
    DetectorConfig detector;
    CameraConfig camera;
    FilterConfig filter;
    int max_faces = 1;  ///< faces followed at once
    /// Look for new faces every this many frames while fewer than max_faces
    /// are followed (every frame while none is).
    int detect_interval = 15;
    /// Confirm a followed face with the detector, on a small crop around it,
    /// every this many frames, and in any frame where what is followed stops
    /// looking like the face of the frame before or the fit doubts it (a
    /// sudden turn, a poor fit). No detection: the face is dropped (on the
    /// periodic check). A detection elsewhere: the face restarts from it, same
    /// id. Catches a tracker that sticks to background after the face left,
    /// or to the side of a head that moved fast. 0: never.
    int verify_interval = 30;
    /// A fit residual above this (eye-corner distances; FaceResult::fit_residual) drops the face and re-detects.
    float max_fit_residual = 0.12f;
    /// Estimate the user's identity from this many well-fitted frames (one
    /// taken every 5 frames), then freeze it. 0: keep the mean face.
    int calibration_frames = 30;
    /// A factor on the fit's expression prior (learned from the dense teacher
    /// labels, docs/expressions.md): below 1 the expressions respond more and
    /// a relaxed face reads less relaxed; above 1 the other way. In (0, 100].
    float expression_prior = 1.0f;
    /// The landmark regression runs from this many starts a few pixels apart
    /// and averages them, 1..9: each start costs one more landmark pass (about
    /// 0.2 ms on one core), and five jitter about half as much as one
    /// (docs/landmarks.md). Three, because the landmark refiner after them
    /// steadies the points too; without the refiner five jitter less.
    int landmark_starts = 3;
    /// Run the CNN file's expression nets (the "cnn" stage). The shipped file
    /// reads 32 ARKit shapes from the face's texture and the landmarks' geometry
    /// and corrects the fit's (the brows, pucker, squint, press; docs/cnn.md) in
    /// about 0.25 ms a frame on one core; false leaves the fit's 15.
    bool cnn_stage = true;
};

/// Throws Error naming the first field of `config` out of range, as the Tracker's
/// constructor does: settings can be checked before anything is loaded or opened.
void validate(const TrackerConfig& config);

/// Throws Error naming the first value of `calibration` out of range (validate(Calibration))
/// or a native neutral or identity whose size is not `face`'s, as Tracker::setCalibration does.
void validate(const Calibration& calibration, const FaceModel& face);

/// One Tracker follows the faces of one video stream. It is not thread-safe:
/// use one per stream (or thread) and share the immutable models between them.
class Tracker {
public:
    /// Throws facetrack::Error when a stage cannot be set up (no detector, no
    /// face model, a config value out of range).
    explicit Tracker(Models models, const TrackerConfig& config = {});
    /// With the application's own face detector instead of the configured one
    /// (config.detector is then unused). The Tracker owns it and calls it from
    /// process() only. Its kind() picks the landmark model's box prior:
    /// "yunet" or "cascade"; any other name uses the YuNet prior, so its boxes
    /// should frame a face as YuNet's do (docs/detector.md).
    Tracker(Models models, const TrackerConfig& config, std::unique_ptr<FaceDetector> detector);
    ~Tracker();
    Tracker(Tracker&&) noexcept;
    Tracker& operator=(Tracker&&) noexcept;

    /// Processes the next frame of the stream into `out`, whose memory is
    /// reused: pass the same FrameResult every frame and tracking allocates
    /// nothing once the number of faces is steady. Returns `out`.
    ///
    /// time_s is the frame's capture time in seconds; it must increase from
    /// frame to frame. The temporal filter steps by the difference; a time
    /// that does not increase (repeated, backwards, NaN) is taken as 1/30 s
    /// after the previous frame. Throws Error on an invalid view.
    FrameResult& process(const ImageView& frame, double time_s, FrameResult& out);

    /// As above, but the caller says where the faces are in this frame (its own
    /// detector or a face picked by the user): the detector does not run. A box
    /// that overlaps a followed face confirms it; any other starts a new face
    /// there (up to max_faces). Followed faces without a box go on being followed.
    FrameResult& process(const ImageView& frame, double time_s, const std::vector<Box>& faces, FrameResult& out);

    /// Convenience: a new FrameResult per frame (allocates).
    FrameResult process(const ImageView& frame, double time_s);

    /// Forgets the identity of every followed face and the calibration's: they
    /// go back to the mean face and estimate it again.
    void resetIdentity();

    /// The user's calibration this Tracker applies (facetrack/calibration.hpp):
    /// neutral, ranges, gains, dead zones, and the identity: the calibration's
    /// own or, when it has none, the first followed face's once estimated.
    /// Save it as the user's profile with saveCalibration().
    Calibration calibration() const;
    /// Applies `calibration` to every face, followed now or found later (one
    /// user at the camera: a face lost and found again keeps it). Its identity,
    /// when given, is taken as the user's face shape instead of estimating one;
    /// when empty, followed faces keep theirs and new ones estimate their own.
    /// Calibration{} turns calibration off. Throws Error, changing nothing, on
    /// a value out of range or a size that does not fit the face model.
    void setCalibration(const Calibration& calibration);

    /// Takes the first followed face's current expression, as estimated
    /// before calibration, as the user's neutral (ask them to relax first);
    /// ranges, gains and dead zones stay, and the eyes' look directions keep
    /// theirs (a relaxed face may look anywhere). No face followed: nothing
    /// changes. resetNeutral() sets every neutral back to 0.
    void calibrateNeutral();
    void resetNeutral();

    /// Forgets every followed face: the next frame is searched from scratch,
    /// as the first of a new stream (e.g. between unrelated photos). Face ids
    /// keep counting up.
    void reset();

    /// Every pipeline stage, in order, with its availability in this build.
    std::vector<StageInfo> stages() const;

    /// The ARKit shapes some available stage estimates (arkitNames() order);
    /// every other weight is always 0 with these models and this configuration.
    std::vector<std::string> estimatedShapes() const;

    const Models& models() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace facetrack
