#include "guided_calibration.hpp"

#include "facetrack/error.hpp"

namespace facetrack::demo {

void GuidedCalibration::start(Tracker& tracker) {
    before_ = tracker.calibration();
    Calibration bare;
    bare.identity = before_.identity;
    tracker.setCalibration(bare);
    capture_.emplace(before_);
    start_ = -1.0;
    step_.reset();
    outcome_.clear();
}

void GuidedCalibration::cancel(Tracker& tracker) {
    if (!running()) return;
    tracker.setCalibration(before_);
    capture_.reset();
    step_.reset();
    outcome_ = "calibration cancelled";
}

bool GuidedCalibration::update(Tracker& tracker, const FrameResult& frame, double time_s) {
    if (!running()) return false;
    if (start_ < 0.0) start_ = time_s;
    const auto& prompts = calibrationPrompts();
    const double t = time_s - start_;
    const auto index = static_cast<std::size_t>(t / kSecondsPerPrompt);
    if (index >= prompts.size()) {
        bool calibrated = true;
        try {
            Calibration result = capture_->result();
            result.identity = tracker.calibration().identity;
            tracker.setCalibration(result);
            outcome_ = "calibrated from " + std::to_string(capture_->frames("neutral")) + " neutral frames";
        } catch (const Error& e) {
            tracker.setCalibration(before_);
            outcome_ = e.what();
            calibrated = false;
        }
        capture_.reset();
        step_.reset();
        return calibrated;
    }
    const double within = t - static_cast<double>(index) * kSecondsPerPrompt;
    step_ = Step{index, prompts.size(), prompts[index].instruction, within / kSecondsPerPrompt, within >= kSettleSeconds};
    if (step_->measuring && !frame.faces.empty() && frame.faces.front().expression) {
        capture_->add(prompts[index].name, *frame.faces.front().expression);
    }
    return false;
}

}  // namespace facetrack::demo
