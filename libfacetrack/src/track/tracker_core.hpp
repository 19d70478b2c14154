#pragma once
// What the public Tracker runs: the track lifecycle (detect, verify,
// re-detect, ids) around an ordered list of stages, each timed under its own
// name. Tests drive it with fake detectors and fake stages.

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
    /// Native expressions a neutral calibration leaves alone (the eyes' look
    /// directions: a neutral face may look anywhere), as a mask over them.
    std::vector<bool> neutral_keeps_native;
};

class TrackerCore {
public:
    TrackerCore(std::unique_ptr<FaceDetector> detector, pipeline::StageList stages, const LifecycleSettings& settings);

    /// One frame: find or confirm faces (the detector, or `boxes` when not
    /// null), run every available stage on every face in list order, drop the
    /// faces a stage lost (and look again in this frame when none is left),
    /// and write the faces and per-stage timings into `out`.
    void process(const ImageView& frame, double time_s, const std::vector<Box>* boxes, FrameResult& out);

    void reset();
    void resetCalibration();
    /// Takes each followed face's current expression as its neutral; off: forgets them.
    void calibrateNeutral(bool on);

    /// "detect", "verify", then the stages, in order.
    std::vector<StageInfo> stages() const;
    /// The native expressions some available stage estimates.
    std::vector<int> estimatedExpressions() const;

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
    void runStages(const pipeline::FrameInput& input, pipeline::FaceTrack& face);
    void dropLost();
    void time(int slot, Clock::time_point start);

    std::unique_ptr<FaceDetector> detector_;
    pipeline::StageList stages_;
    std::vector<bool> available_;
    std::vector<std::string> names_;  // per timing slot
    std::vector<double> ms_;          // per timing slot, this frame
    std::vector<bool> ran_;
    LifecycleSettings settings_;

    std::vector<pipeline::FaceTrack> tracks_;
    cv::Mat gray_, crop_;     // reused frame to frame
    std::vector<float> appearance_;
    int next_id_ = 1;
    long frame_index_ = 0;
    double last_time_;
};

}  // namespace facetrack::track
