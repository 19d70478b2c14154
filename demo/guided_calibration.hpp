#pragma once
// The app's guided calibration: each of calibrationPrompts() is shown for a
// few seconds (the first second to get there, the rest measured); at the end
// the capture becomes the Tracker's calibration. Timed by the frames' own
// timestamps, so a clip calibrates the same at any playback speed.

#include "facetrack/calibration.hpp"
#include "facetrack/tracker.hpp"

#include <optional>
#include <string>

namespace facetrack::demo {

class GuidedCalibration {
public:
    static constexpr double kSecondsPerPrompt = 3.0;
    static constexpr double kSettleSeconds = 1.0;

    /// Starts a capture: the tracker's calibration is set aside (its identity
    /// kept) so that the frames give the weights as estimated.
    void start(Tracker& tracker);
    bool running() const { return capture_.has_value(); }

    /// A tracked frame at `time_s`. After the last prompt the capture becomes
    /// the tracker's calibration and true is returned (then save it); a
    /// capture without a neutral face (no face seen) restores the old one and
    /// says so in outcome().
    bool update(Tracker& tracker, const FrameResult& frame, double time_s);
    void cancel(Tracker& tracker);

    /// The prompt shown now (running only): its index, instruction and the
    /// share of its time gone.
    struct Step {
        std::size_t index = 0, count = 0;
        std::string instruction;
        double progress = 0.0;
        bool measuring = false;  ///< past the settling second
    };
    std::optional<Step> step() const { return step_; }
    /// What the last capture measured, or why it failed.
    const std::string& outcome() const { return outcome_; }

private:
    std::optional<CalibrationCapture> capture_;
    Calibration before_;
    double start_ = -1.0;
    std::optional<Step> step_;
    std::string outcome_;
};

}  // namespace facetrack::demo
