#include "neutral/neutral_stage.hpp"

#include <algorithm>
#include <optional>

namespace facetrack::neutral {

namespace {

/// w' = (w - w0) / (1 - w0) clamped to [0, 1] for every weight of `e` but the ones `keepArkit` /
/// `keepNative` mark; a weight whose neutral reads 0.99 or more is left as it is. No allocation.
void relativeToNeutral(const ExpressionResult& neutral, const std::vector<bool>& keepArkit, const std::vector<bool>& keepNative,
                       ExpressionResult& e) {
    const auto rescale = [](float w, float w0) { return w0 < 0.99f ? std::clamp((w - w0) / (1.f - w0), 0.f, 1.f) : w; };
    for (std::size_t k = 0; k < e.arkit.size(); ++k) {
        if (k < keepArkit.size() && keepArkit[k]) continue;
        e.arkit[k] = rescale(e.arkit[k], neutral.arkit[k]);
    }
    if (neutral.native.size() != e.native.size()) return;
    for (std::size_t k = 0; k < e.native.size(); ++k) {
        if (k < keepNative.size() && keepNative[k]) continue;
        e.native[k] = rescale(e.native[k], neutral.native[k]);
    }
}

struct NeutralFaceState final : pipeline::StageState {
    std::optional<ExpressionResult> last;     ///< this frame's weights before rescaling
    std::optional<ExpressionResult> neutral;  ///< empty: off
};

/// The eyeLook shapes of `names`: a neutral calibration leaves them alone.
template <class Names>
std::vector<bool> eyeLook(const Names& names) {
    std::vector<bool> mask;
    for (const auto& name : names) mask.push_back(std::string_view(name).rfind("eyeLook", 0) == 0);
    return mask;
}

class NeutralStage final : public pipeline::Stage {
public:
    explicit NeutralStage(const FaceModel& model) : keep_arkit_(eyeLook(arkitNames())), keep_native_(eyeLook(model.expressionNames())) {}

    StageInfo info() const override { return {"neutral", true, "the user's neutral expression subtracted, once calibrated"}; }

    pipeline::Contract contract() const override { return {pipeline::Field::Expression, pipeline::Field::Expression}; }

    std::unique_ptr<pipeline::StageState> newFaceState() const override { return std::make_unique<NeutralFaceState>(); }

    pipeline::Outcome run(const pipeline::FrameInput&, pipeline::FaceTrack& face, pipeline::StageState* state) override {
        auto& s = static_cast<NeutralFaceState&>(*state);
        if (!face.result.expression) return pipeline::Outcome::Ok;
        s.last = face.result.expression;  // copies into place: no allocation once sized
        if (s.neutral) relativeToNeutral(*s.neutral, keep_arkit_, keep_native_, *face.result.expression);
        return pipeline::Outcome::Ok;
    }

    void calibrateNeutral(pipeline::StageState* state, bool on) const override {
        auto& s = static_cast<NeutralFaceState&>(*state);
        if (on && s.last) {
            s.neutral = s.last;
        } else {
            s.neutral.reset();
        }
    }

private:
    std::vector<bool> keep_arkit_, keep_native_;
};

}  // namespace

std::unique_ptr<pipeline::Stage> makeNeutralStage(std::shared_ptr<const FaceModel> model) { return std::make_unique<NeutralStage>(*model); }

}  // namespace facetrack::neutral
