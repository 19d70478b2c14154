#include "calibration/calibration_stage.hpp"

#include "calibration/neutral.hpp"
#include "facetrack/error.hpp"

#include <algorithm>
#include <optional>

namespace facetrack::calibration {

namespace {

struct CalibrationFaceState final : pipeline::StageState {
    std::optional<ExpressionResult> last;  ///< this frame's weights before calibration
};

/// For each of the face model's own expressions, the ARKit shape it drives
/// (FaceModel::toArkit of it alone), or -1 for those that drive none.
std::vector<int> arkitOfNative(const FaceModel& model) {
    std::vector<int> out;
    std::vector<float> one(model.expressionNames().size(), 0.f);
    for (std::size_t k = 0; k < one.size(); ++k) {
        one[k] = 1.f;
        const auto arkit = model.toArkit(one);
        const auto driven = std::find_if(arkit.begin(), arkit.end(), [](float w) { return w > 0.f; });
        out.push_back(driven == arkit.end() ? -1 : static_cast<int>(driven - arkit.begin()));
        one[k] = 0.f;
    }
    return out;
}

/// The ARKit shapes a captured neutral leaves alone.
std::vector<bool> keptNeutrals() {
    std::vector<bool> mask;
    for (const auto name : arkitNames()) mask.push_back(keepsItsNeutral(name));
    return mask;
}

class CalibrationStage final : public pipeline::Stage {
public:
    explicit CalibrationStage(const FaceModel& model)
        : native_count_(model.expressionNames().size()), arkit_of_native_(arkitOfNative(model)), kept_(keptNeutrals()) {}

    StageInfo info() const override { return {"calibration", true, "the user's calibration applied: neutral, range, gain, dead zone"}; }

    pipeline::Contract contract() const override { return {pipeline::Field::Expression, pipeline::Field::Expression}; }

    std::unique_ptr<pipeline::StageState> newFaceState() const override { return std::make_unique<CalibrationFaceState>(); }

    pipeline::Outcome run(const pipeline::FrameInput&, pipeline::FaceTrack& face, pipeline::StageState* state) override {
        auto& s = static_cast<CalibrationFaceState&>(*state);
        if (!face.result.expression) return pipeline::Outcome::Ok;
        s.last = face.result.expression;  // copies into place: no allocation once sized
        if (passthrough_) return pipeline::Outcome::Ok;
        ExpressionResult& e = *face.result.expression;
        for (std::size_t k = 0; k < e.arkit.size(); ++k) e.arkit[k] = calibrated(shapes_[k], e.arkit[k]);
        if (e.native.size() == native_count_) {
            for (std::size_t k = 0; k < e.native.size(); ++k) e.native[k] = calibrated(native_[k], e.native[k]);
        }
        return pipeline::Outcome::Ok;
    }

    void setCalibration(const Calibration& calibration, const std::vector<pipeline::StageState*>&) override {
        if (!calibration.native_neutral.empty() && calibration.native_neutral.size() != native_count_) {
            throw Error("calibration: native_neutral has " + std::to_string(calibration.native_neutral.size()) +
                        " weights, the face model " + std::to_string(native_count_));
        }
        shapes_ = calibration.shapes;
        passthrough_ = shapes_ == Calibration{}.shapes && calibration.native_neutral.empty();
        // A native weight: its own neutral, and the range, gain and dead zone of the ARKit shape it
        // drives (so that a mesh posed from them moves as the ARKit weights sent do); one that drives
        // a shape whose neutral is kept (the eyes' look) follows that shape wholly.
        native_.assign(native_count_, ShapeCalibration{});
        for (std::size_t k = 0; k < native_count_; ++k) {
            ShapeCalibration& s = native_[k];
            const int j = arkit_of_native_[k];
            if (j >= 0) s = shapes_[static_cast<std::size_t>(j)];
            if (j >= 0 && kept_[static_cast<std::size_t>(j)]) continue;
            s.neutral = calibration.native_neutral.empty() ? 0.f : calibration.native_neutral[k];
            if (s.full <= s.neutral) s.full = 1.f;  // one side's neutral above the pair's full: its neutral alone
        }
    }

    void captureNeutral(const pipeline::StageState* state, Calibration& into) const override {
        const auto& s = static_cast<const CalibrationFaceState&>(*state);
        if (!s.last) return;
        for (std::size_t k = 0; k < s.last->arkit.size(); ++k) {
            if (kept_[k]) continue;
            ShapeCalibration& shape = into.shapes[k];
            shape.neutral = std::min(s.last->arkit[k], shape.full - kMinRange);
            shape.neutral = std::max(shape.neutral, 0.f);
        }
        into.native_neutral.assign(s.last->native.size(), 0.f);
        for (std::size_t k = 0; k < s.last->native.size(); ++k) into.native_neutral[k] = std::min(s.last->native[k], 1.f - kMinRange);
    }

private:
    // A captured neutral stays this far below the shape's full value.
    static constexpr float kMinRange = 0.01f;
    std::size_t native_count_;
    std::vector<int> arkit_of_native_;                              ///< per native expression, the ARKit shape it drives, or -1
    std::vector<bool> kept_;                                        ///< per ARKit shape: a captured neutral leaves it alone
    std::array<ShapeCalibration, kArkitBlendshapeCount> shapes_{};  ///< how each ARKit weight is reported
    std::vector<ShapeCalibration> native_;                          ///< how each native weight is reported
    bool passthrough_ = true;                                       ///< the calibration leaves every weight as it is
};

}  // namespace

std::unique_ptr<pipeline::Stage> makeCalibrationStage(std::shared_ptr<const FaceModel> model) {
    return std::make_unique<CalibrationStage>(*model);
}

}  // namespace facetrack::calibration
