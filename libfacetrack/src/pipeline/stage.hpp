#pragma once
// The internal stage interface. The Tracker holds an ordered list of stages
// and runs them, in that order, on every followed face of every frame; each
// stage reads what earlier stages wrote and writes its own fields
// (docs/architecture.md, "Adding a stage").
//
//   frame ──> [landmarks] ──> [refine] ──> [fit] ──> [cnn] ──> [gaze] ──> [filter] ──> FaceResult
//                 ^              │
//                 └─ next_start ─┘   (the fitted face's projection starts the next frame's search)

#include "fit/camera.hpp"

#include "facetrack/image.hpp"
#include "facetrack/result.hpp"
#include "facetrack/tracker.hpp"

#include <opencv2/core.hpp>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace facetrack::pipeline {

/// One frame as every stage sees it.
struct FrameInput {
    ImageView colour;     ///< the caller's pixels, in the caller's PixelFormat
    const cv::Mat& gray;  ///< 8-bit grey, converted once per frame
    fit::Camera camera;   ///< the pinhole model for this frame's size
    double dt = 0.0;      ///< seconds since the previous frame (> 0)
};

/// What a stage keeps for one face from frame to frame (a fitter, filters, ...).
struct StageState {
    virtual ~StageState() = default;
};

/// One followed face: the Tracker's lifecycle fields, and what the stages
/// pass each other.
struct FaceTrack {
    // Lifecycle (the Tracker's).
    int id = 0;
    bool fresh = true;      ///< found (again) this frame by the detector or a caller's box: start from `box`
    int age = 0;            ///< frames reported so far
    Box box;                ///< detector box while fresh, then wherever a stage locates the face
    bool located = false;   ///< a stage (or the detector) placed the face in this frame
    bool lost = false;      ///< a stage or the verification lost it this frame: dropped
    /// A stage doubts, this frame, that it still follows the face (a jump, a
    /// poor fit): the Tracker runs it again (as for `unsettled`), then checks
    /// it with the detector in this very frame.
    bool doubtful = false;
    /// A stage's answer moved so far from the previous frame's (a fast turn)
    /// that the stages before it, started from the previous frame, may have
    /// stopped short: the Tracker runs them and it once more, from this answer.
    bool unsettled = false;
    /// The face's box in the last frame, small and standardised (the Tracker's
    /// check that what it follows still looks like what it followed).
    /// Empty when the last frame gave none.
    std::vector<float> appearance;

    // Between stages.
    /// Stages write their fields here; it lives as long as the face, so its
    /// vectors keep their memory from frame to frame.
    FaceResult result;
    /// Where the next frame's landmark search starts (written by the fit: its
    /// projection). Empty: from `box`.
    std::optional<Landmarks68> next_start;
    /// One per stage, in list order; null for stages that keep nothing.
    std::vector<std::unique_ptr<StageState>> states;
    /// The user's neutral expression (Tracker::calibrateNeutral): the output's
    /// weights are reported relative to it. Empty: off.
    std::optional<ExpressionResult> neutral;

    /// A stage found the face at `where` in this frame.
    void locate(const Box& where) {
        box = where;
        located = true;
    }
};

class Stage {
public:
    virtual ~Stage() = default;
    /// The stage's entry in Tracker::stages(): its name (also its timing's
    /// label; keep it under 16 characters, std::string's inline capacity),
    /// whether it can run, and what implements it or why it cannot.
    virtual StageInfo info() const = 0;
    /// New per-face state for a face just found; nullptr when the stage keeps none.
    virtual std::unique_ptr<StageState> newFaceState() const { return nullptr; }
    /// Runs on one face of one frame: reads what earlier stages wrote into
    /// `face`, writes its own fields into face.result. Returns false when the
    /// face is lost (its own failure checks): the Tracker drops it and looks
    /// for faces again. Called only when info().available. Must not allocate
    /// once the face is followed (docs/architecture.md).
    virtual bool run(const FrameInput& frame, FaceTrack& face, StageState* state) = 0;
    /// Forget per-user estimates (Tracker::resetIdentity).
    virtual void resetCalibration(StageState* /*state*/) const {}
    /// The face model's native expressions this stage estimates (indices into
    /// FaceModel::expressionNames()); none for stages that write no expression.
    virtual std::vector<int> estimatedExpressions() const { return {}; }
};

using StageList = std::vector<std::unique_ptr<Stage>>;

/// A stage that is not built yet: listed, never run, its fields stay empty.
std::unique_ptr<Stage> notAvailable(const char* name, const std::string& why);

}  // namespace facetrack::pipeline
