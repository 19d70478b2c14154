#include "calibration/calibration_stage.hpp"

#include "facetrack/error.hpp"

#include <algorithm>
#include <optional>

namespace facetrack::calibration {

namespace {

struct CalibrationFaceState final : pipeline::StageState {
    std::optional<ExpressionResult> last;  ///< this frame's weights before calibration
};

/// The eyeLook shapes of `names`: a captured neutral leaves them alone.
template <class Names>
std::vector<bool> eyeLook(const Names& names) {
    std::vector<bool> mask;
    for (const auto& name : names) mask.push_back(std::string_view(name).rfind("eyeLook", 0) == 0);
    return mask;
}

class CalibrationStage final : public pipeline::Stage {
public:
    explicit CalibrationStage(const FaceModel& model)
        : native_count_(model.expressionNames().size()),
          eye_look_(eyeLook(arkitNames())),
          native_eye_look_(eyeLook(model.expressionNames())) {}

    StageInfo info() const override { return {"calibration", true, "the user's calibration applied: neutral, range, gain, dead zone"}; }

    pipeline::Contract contract() const override { return {pipeline::Field::Expression, pipeline::Field::Expression}; }

    std::unique_ptr<pipeline::StageState> newFaceState() const override { return std::make_unique<CalibrationFaceState>(); }

    pipeline::Outcome run(const pipeline::FrameInput&, pipeline::FaceTrack& face, pipeline::StageState* state) override {
        auto& s = static_cast<CalibrationFaceState&>(*state);
        if (!face.result.expression) return pipeline::Outcome::Ok;
        s.last = face.result.expression;  // copies into place: no allocation once sized
        if (passthrough_) return pipeline::Outcome::Ok;
        ExpressionResult& e = *face.result.expression;
        for (std::size_t k = 0; k < e.arkit.size(); ++k) e.arkit[k] = calibrated(calibration_.shapes[k], e.arkit[k]);
        const std::vector<float>& w0 = calibration_.native_neutral;
        if (w0.size() == e.native.size()) {
            for (std::size_t k = 0; k < e.native.size(); ++k) e.native[k] = std::clamp((e.native[k] - w0[k]) / (1.f - w0[k]), 0.f, 1.f);
        }
        return pipeline::Outcome::Ok;
    }

    void setCalibration(const Calibration& calibration, const std::vector<pipeline::StageState*>&) override {
        if (!calibration.native_neutral.empty() && calibration.native_neutral.size() != native_count_) {
            throw Error("calibration: native_neutral has " + std::to_string(calibration.native_neutral.size()) +
                        " weights, the face model " + std::to_string(native_count_));
        }
        calibration_ = calibration;
        passthrough_ = calibration_.shapes == Calibration{}.shapes && calibration_.native_neutral.empty();
    }

    void captureNeutral(const pipeline::StageState* state, Calibration& into) const override {
        const auto& s = static_cast<const CalibrationFaceState&>(*state);
        if (!s.last) return;
        for (std::size_t k = 0; k < s.last->arkit.size(); ++k) {
            if (eye_look_[k]) continue;
            ShapeCalibration& shape = into.shapes[k];
            shape.neutral = std::min(s.last->arkit[k], shape.full - kMinRange);
            shape.neutral = std::max(shape.neutral, 0.f);
        }
        into.native_neutral.assign(s.last->native.size(), 0.f);
        for (std::size_t k = 0; k < s.last->native.size(); ++k) {
            if (!native_eye_look_[k]) into.native_neutral[k] = std::min(s.last->native[k], 1.f - kMinRange);
        }
    }

private:
    // A captured neutral stays this far below the shape's full value.
    static constexpr float kMinRange = 0.01f;
    std::size_t native_count_;
    std::vector<bool> eye_look_, native_eye_look_;
    Calibration calibration_;
    bool passthrough_ = true;  ///< the calibration leaves every weight as it is
};

}  // namespace

std::unique_ptr<pipeline::Stage> makeCalibrationStage(std::shared_ptr<const FaceModel> model) {
    return std::make_unique<CalibrationStage>(*model);
}

}  // namespace facetrack::calibration
