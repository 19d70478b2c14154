#pragma once
// The internal stage interface. The Tracker holds an ordered list of stages
// and runs them, in that order, on every followed face of every frame. Each
// stage declares the fields it reads and writes (its Contract, as a MediaPipe
// calculator declares its streams); the Tracker checks at construction that
// every read is written by an earlier available stage, and tells each stage
// what the stages before it provide (Stage::connect). docs/architecture.md,
// "Adding a stage".
//
//   frame ──> [landmarks] ──> [refine] ──> [fit] ──> [cnn] ──> [gaze] ──> [filter] ──> [calibration] ──> FaceResult
//                 ^                          │
//                 └──────── next_start ──────┘   (the fitted face's projection starts the next frame's search)

#include "core/camera.hpp"

#include "facetrack/calibration.hpp"
#include "facetrack/image.hpp"
#include "facetrack/result.hpp"

#include <opencv2/core.hpp>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace facetrack::pipeline {

/// One frame as every stage sees it.
struct FrameInput {
    ImageView colour;     ///< the caller's pixels, in the caller's PixelFormat
    const cv::Mat& gray;  ///< 8-bit grey, converted once per frame
    core::Camera camera;  ///< the pinhole model for this frame's size
    double dt = 0.0;      ///< seconds since the previous frame (> 0)
};

/// The fields of a face that stages pass each other: what a Contract names.
enum class Field : std::uint32_t {
    Landmarks = 1u << 0,   ///< FaceResult::landmarks, and the face's box (FaceTrack::locate)
    Pose = 1u << 1,        ///< FaceResult::pose
    Expression = 1u << 2,  ///< FaceResult::expression
    Identity = 1u << 3,    ///< FaceResult::identity, identity_calibrated
    Fit = 1u << 4,         ///< FaceResult::fit_residual, confidence
    Gaze = 1u << 5,        ///< FaceResult::gaze
    Raw = 1u << 6,         ///< FaceResult::raw
    NextStart = 1u << 7,   ///< FaceTrack::next_start
};

/// A set of Fields.
class Fields {
public:
    constexpr Fields() = default;
    constexpr Fields(Field f) : bits_(static_cast<std::uint32_t>(f)) {}  // NOLINT: a field is a set of one
    constexpr Fields operator|(Fields o) const { return Fields(bits_ | o.bits_); }
    constexpr Fields operator-(Fields o) const { return Fields(bits_ & ~o.bits_); }
    constexpr bool empty() const { return bits_ == 0; }
    constexpr bool has(Field f) const { return (bits_ & static_cast<std::uint32_t>(f)) != 0; }
    constexpr bool operator==(Fields o) const { return bits_ == o.bits_; }
    /// "landmarks, pose": the names, in Field order.
    std::string names() const;

private:
    constexpr explicit Fields(std::uint32_t bits) : bits_(bits) {}
    std::uint32_t bits_ = 0;
};
constexpr Fields operator|(Field a, Field b) { return Fields(a) | b; }

/// What a stage reads and writes, and the expressions it estimates.
struct Contract {
    Contract() = default;
    Contract(Fields reads_, Fields writes_, std::vector<int> expressions_ = {}, bool smoothed = false)
        : reads(reads_), writes(writes_), expressions(std::move(expressions_)), expressions_smoothed(smoothed) {}

    /// Needed from an earlier stage in the same frame: without a stage that
    /// writes them, this one is not available.
    Fields reads;
    Fields writes;
    /// The face model's native expressions it writes (indices into
    /// FaceModel::expressionNames()): the shapes it estimates.
    std::vector<int> expressions;
    /// Its expressions carry their own temporal estimate: later smoothing
    /// leaves them as they are.
    bool expressions_smoothed = false;
};

/// What the available stages before one provide: the Tracker builds it from
/// their contracts and hands it to each stage at construction.
struct Upstream {
    Fields written;
    std::vector<int> expressions;           ///< estimated by an earlier stage
    std::vector<int> smoothed_expressions;  ///< of those, the ones with their own temporal estimate
};

/// Adds what `stage` (available, connected) writes and estimates to `upstream`:
/// how the Tracker builds each stage's Upstream, and how a test or benchmark
/// connects a stage it runs alone.
void provide(const Contract& contract, Upstream& upstream);

/// What a run says of the face, from good to bad. The Tracker's re-run policy
/// (TrackerCore::follow) acts on it.
enum class Outcome {
    Ok,
    /// The answer moved so far from the previous frame's (a fast turn) that
    /// the stages before, started from the previous frame, may have stopped
    /// short: they run once more, from this answer.
    Unsettled,
    /// The stage doubts that it still follows the face (a jump, a poor fit):
    /// the stages run once more, then the detector checks the face.
    Doubtful,
    /// The face is not there (the stage's own failure checks): dropped.
    Lost,
};

/// The worse of two outcomes.
constexpr Outcome worse(Outcome a, Outcome b) { return a > b ? a : b; }

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
    bool lost = false;      ///< lost this frame: dropped at the end of the pass
    bool doubtful = false;  ///< a stage or the appearance check doubts it this frame: the detector checks it
    /// The face's box in the last frame, small and standardised (the Tracker's
    /// check that what it follows still looks like what it followed).
    /// Empty when the last frame gave none.
    std::vector<float> appearance;

    // Between stages (the Fields of a Contract).
    /// Stages write their fields here; it lives as long as the face, so its
    /// vectors keep their memory from frame to frame.
    FaceResult result;
    /// Where the next frame's landmark search starts (Field::NextStart: the
    /// fit's projection). Empty: from `box`.
    std::optional<Landmarks68> next_start;
    /// One per stage, in list order; null for stages that keep nothing.
    std::vector<std::unique_ptr<StageState>> states;

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
    /// whether it can run with what it was given, and what implements it or
    /// why it cannot.
    virtual StageInfo info() const = 0;
    /// What it reads and writes (from construction on), and the expressions
    /// it estimates (once connected).
    virtual Contract contract() const = 0;
    /// Called once at construction, in list order, with what the available
    /// stages before it provide, when its reads are among them.
    virtual void connect(const Upstream& /*upstream*/) {}
    /// New per-face state for a face just found; nullptr when the stage keeps none.
    virtual std::unique_ptr<StageState> newFaceState() const { return nullptr; }
    /// Runs on one face of one frame: reads its Contract's reads from `face`,
    /// writes its writes. Called only when available and connected. Must not
    /// allocate once the face is followed (docs/architecture.md).
    virtual Outcome run(const FrameInput& frame, FaceTrack& face, StageState* state) = 0;
    /// Forget per-user estimates (Tracker::resetIdentity).
    virtual void resetIdentity(StageState* /*state*/) const {}
    /// The user's calibration changed (Tracker::setCalibration): keep what
    /// this stage applies, for the followed faces (`faces`: this stage's state
    /// of each) and for faces found later. Throws Error, changing nothing,
    /// when the calibration does not fit the stage's models.
    virtual void setCalibration(const Calibration& /*calibration*/, const std::vector<StageState*>& /*faces*/) {}
    /// Write the face's current expression, as estimated before calibration,
    /// into `into` as its neutral (Tracker::calibrateNeutral).
    virtual void captureNeutral(const StageState* /*state*/, Calibration& /*into*/) const {}
};

using StageList = std::vector<std::unique_ptr<Stage>>;

/// A stage that cannot run here: listed, never run, its fields stay empty.
std::unique_ptr<Stage> notAvailable(const char* name, const std::string& why);

}  // namespace facetrack::pipeline
