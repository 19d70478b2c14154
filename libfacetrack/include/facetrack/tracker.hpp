#pragma once
/// \file
/// The Tracker wires the stages into one pipeline:
///   frame -> detect (when nothing is tracked) -> landmarks -> fit -> CNN -> gaze -> filter -> result
/// docs/architecture.md shows the data flow. Stages not built yet report
/// "not available" and leave their fields of FaceResult empty.

#include "facetrack/detector.hpp"
#include "facetrack/face_model.hpp"
#include "facetrack/image.hpp"
#include "facetrack/landmark_model.hpp"
#include "facetrack/result.hpp"

#include <memory>
#include <string>
#include <vector>

namespace facetrack {

struct StageInfo {
    std::string name;       ///< "detect", "landmarks", ...
    bool available = false;
    std::string detail;     ///< what implements it, or why it is not available
};

/// The models a Tracker uses, loaded once and shared (immutable) by any
/// number of Trackers on any threads.
struct Models {
    std::shared_ptr<const FaceModel> face;            ///< required
    std::shared_ptr<const LandmarkModel> landmarks;   ///< null: the landmarks stage is not available

    /// The shipped models from modelDirectory(). A missing landmark model
    /// leaves `landmarks` null (and is logged); any other problem throws Error.
    static Models loadDefault();
};

struct TrackerConfig {
    DetectorConfig detector;
    int max_faces = 1;  ///< faces followed at once
};

/// One Tracker follows the faces of one video stream. It is not thread-safe;
/// use one per thread and share the (immutable) FaceModel between them.
class Tracker {
public:
    /// Throws facetrack::Error when a stage cannot be set up (no detector, no face model).
    explicit Tracker(Models models, const TrackerConfig& config = {});
    ~Tracker();
    Tracker(Tracker&&) noexcept;
    Tracker& operator=(Tracker&&) noexcept;

    /// Processes the next frame of the stream; time_s is its timestamp in
    /// seconds (used by temporal filtering). Throws Error on an invalid view.
    FrameResult process(const ImageView& frame, double time_s);

    /// Every pipeline stage, in order, with its availability in this build.
    std::vector<StageInfo> stages() const;

    const Models& models() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace facetrack
