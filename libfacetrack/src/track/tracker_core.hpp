#pragma once
// What the public Tracker runs: the track lifecycle (detect, verify,
// re-detect, ids) around an ordered list of stages, each timed under its own
// name. At construction it checks the stages' contracts (pipeline/stage.hpp):
// a stage whose reads no earlier available stage writes is not available.
// Tests drive it with fake detectors and fake stages.

#include "pipeline/stage.hpp"

#include "facetrack/detector.hpp"
#include "facetrack/tracker.hpp"

#include <chrono>
#include <memory>
#include <optional>
#include <vector>

namespace facetrack::track {

struct LifecycleSettings {
    int max_faces = 1;
    int detect_interval = 15;  ///< TrackerConfig::detect_interval
    int verify_interval = 30;  ///< TrackerConfig::verify_interval
    CameraConfig camera;
};

class TrackerCore {
public:
    TrackerCore(std::unique_ptr<FaceDetector> detector, pipeline::StageList stages, const LifecycleSettings& settings);

    /// One frame: find or confirm faces (the detector, or `boxes` when not
    /// null), follow every face through the stages (follow()), drop the faces
    /// lost (and look again in this frame when none is left), and write the
    /// faces and per-stage timings into `out`.
    void process(const ImageView& frame, double time_s, const std::vector<Box>* boxes, FrameResult& out);

    void reset();
    void resetIdentity();
    /// Hands the user's calibration to every stage, for the followed faces and later ones.
    void setCalibration(const Calibration& calibration);
    /// Writes the first followed face's expression, as estimated before
    /// calibration, into `into` as its neutral; false when no face is followed.
    bool captureNeutral(Calibration& into) const;
    /// The first followed face's result as of the last frame; null when none.
    const FaceResult* firstFace() const;

    /// "detect", "verify", then the stages, in order.
    std::vector<StageInfo> stages() const;
    /// The native expressions some available stage estimates.
    const std::vector<int>& estimatedExpressions() const { return expressions_; }

private:
    using Clock = std::chrono::steady_clock;
    static constexpr int kDetect = 0, kVerify = 1, kFirstStage = 2;  // timing slots

    void addFace(const Box& box, float score);
    void detect(const ImageView& frame);
    /// The detection nearest the face's centre on a crop around it, in frame pixels.
    std::optional<Box> findAgain(const pipeline::FaceTrack& face);
    /// Why a followed face is checked: now and then (nothing found: lost),
    /// because a stage doubts it (nothing found: kept, as blur hides faces from
    /// the detector too; found: it must agree more closely), or because a stage
    /// could not place it (nothing found: lost; found: it restarts from there
    /// wherever the box was).
    enum class Check { Periodic, InDoubt, Unplaced };
    /// Checks a followed face with the detector. Found where the face's box
    /// does not agree (or, Unplaced, anywhere near): the face restarts from the
    /// detection (fresh, with its id and its stages' state; returns true), or is
    /// lost when another followed face is there already.
    bool verify(pipeline::FaceTrack& face, Check why);
    /// The re-run policy, in one place, for one face of one frame. The face
    /// runs the stages (runStages: a second sweep when a stage doubts it or
    /// it turned fast). Lost while followed, the detector looks where it was
    /// (Check::Unplaced): found, the face restarts there and runs once more.
    /// Its box no longer looking like the last frame's puts it in doubt. In
    /// doubt while followed, the detector checks it (Check::InDoubt): seen
    /// elsewhere, it restarts there and runs once more. So a face sweeps the
    /// stages at most three times a frame.
    void follow(const pipeline::FrameInput& input, pipeline::FaceTrack& face);
    /// The stages in list order on `face`, once or twice (a doubt or a turn).
    pipeline::Outcome runStages(const pipeline::FrameInput& input, pipeline::FaceTrack& face);
    /// One sweep over the stages; stops at a lost face, and, when
    /// `stopAtDoubt`, at the first stage that doubts or unsettles it.
    /// Returns the worst outcome met.
    pipeline::Outcome sweep(const pipeline::FrameInput& input, pipeline::FaceTrack& face, bool stopAtDoubt);
    /// Validates the frame, starts its clock and timings; the stages' view of it.
    pipeline::FrameInput beginFrame(const ImageView& frame, double time_s, FrameResult& out);
    /// New faces from `boxes`, or from the detector while fewer than
    /// max_faces are followed (every detect_interval frames, every frame
    /// while none is). Returns whether it looked.
    bool findFaces(const ImageView& frame, const std::vector<Box>* boxes);
    /// Checks each followed face with the detector every verify_interval frames.
    void verifyNowAndThen(const ImageView& frame);
    void ensureGray(const ImageView& frame);
    /// The faces and the stages' timings of this frame into `out`.
    void report(FrameResult& out);
    void dropLost();
    void time(int slot, Clock::time_point start);

    std::unique_ptr<FaceDetector> detector_;
    pipeline::StageList stages_;
    std::vector<StageInfo> infos_;    // per stage, as checked against the contracts
    std::vector<int> expressions_;    // estimated by some available stage
    std::vector<std::string> names_;  // per timing slot
    std::vector<double> ms_;          // per timing slot, this frame
    std::vector<bool> ran_;
    LifecycleSettings settings_;

    std::vector<pipeline::FaceTrack> tracks_;
    cv::Mat gray_, crop_;      // reused frame to frame
    bool gray_ready_ = false;  // gray_ holds this frame
    std::vector<float> appearance_;
    int next_id_ = 1;
    long frame_index_ = 0;
    double last_time_;
};

}  // namespace facetrack::track
