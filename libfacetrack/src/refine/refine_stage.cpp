#include "refine/refine_stage.hpp"

#include "core/shape2d.hpp"
#include "model/internals.hpp"
#include "nn/refiner_model_data.hpp"
#include "nn/patch_net.hpp"
#include "refine/landmark_refiner.hpp"

#include <array>
#include <optional>

namespace facetrack::refine {

namespace {

/// A second round where the first trusts the net beyond its share (landmark_refiner.hpp).
constexpr int kMaxRounds = 2;

/// Per face: the trust g of the previous frame, averaged into this one's (landmark_refiner.hpp).
struct RefineFaceState final : pipeline::StageState {
    float trust = 0.f;
};

class RefineStage final : public pipeline::Stage {
public:
    explicit RefineStage(std::shared_ptr<const RefinerModel> model)
        : model_(std::move(model)),
          layout_(makeRefinerLayout(model::dataOf(*model_))),
          net_(model::dataOf(*model_).net, layout_.size, 2 * core::kLandmarks, "landmark refiner '" + model_->sourcePath() + "'") {
        if (!model::dataOf(*model_).side_net.empty()) {
            side_layout_ = makeSideLayout(model::dataOf(*model_));
            side_net_.emplace(model::dataOf(*model_).side_net, side_layout_.size, 2 * static_cast<int>(kRightSide.size()),
                              "brow and eye refiner '" + model_->sourcePath() + "'", 2);
        }
    }

    StageInfo info() const override {
        const std::string trust = layout_.trust_to > layout_.trust_from ? ", alone where it disagrees with LBF by " +
                                                                              std::to_string(100.f * layout_.trust_to).substr(0, 3) + " %"
                                                                        : "";
        const std::string sides = side_net_ ? "; brows and eyes again in a " + std::to_string(side_layout_.size) + " px patch per side"
                                            : "";
        return {"refine", true,
                "CNN landmark refiner, " + std::to_string(layout_.size) + " px patch, mean share " +
                    std::to_string(layout_.share.mean()).substr(0, 4) + trust + sides + "; nets on the " + net_.engineName() + " (" +
                    model_->sourcePath() + ")"};
    }

    std::unique_ptr<pipeline::StageState> newFaceState() const override { return std::make_unique<RefineFaceState>(); }

    pipeline::Contract contract() const override { return {pipeline::Field::Landmarks, pipeline::Field::Landmarks}; }

    pipeline::Outcome run(const pipeline::FrameInput& frame, pipeline::FaceTrack& face, pipeline::StageState* state) override {
        if (!face.result.landmarks) return pipeline::Outcome::Ok;
        const core::Shape68 lbf = core::fromLandmarks68(*face.result.landmarks);
        float& trust = static_cast<RefineFaceState&>(*state).trust;
        const float previous = trust;
        core::Shape68 refined = lbf;
        // Round 2 only where the net is trusted beyond its share: there LBF's points, which aligned the patch, are in doubt.
        for (int round = 0; round < kMaxRounds && (round == 0 || trust > 0.f); ++round) {
            const core::Similarity toFrame = patchToFrame(layout_, refined);
            warpAligned(layout_, frame.gray, toFrame, patch_);
            const core::Shape68 net = netLandmarks(layout_, toFrame, net_.predict(patch_));
            if (!net.allFinite()) break;
            const float now = netTrust(layout_, net, lbf);
            trust = face.fresh ? now : 0.5f * (now + previous);
            refined = blendedLandmarks(layout_, net, lbf, trust);
        }
        if (side_net_ && refined.allFinite()) refineSides(side_layout_, *side_net_, frame.gray, side_patches_, refined);
        face.result.landmarks = core::toLandmarks68(refined);
        face.locate(core::boundsOf(refined));
        return pipeline::Outcome::Ok;
    }

private:
    std::shared_ptr<const RefinerModel> model_;
    RefinerLayout layout_;
    nn::PatchNet net_;
    SideLayout side_layout_;
    std::optional<nn::PatchNet> side_net_;  ///< the brow and eye refiner, if the model has one
    cv::Mat patch_;
    std::array<cv::Mat, 2> side_patches_;  // each its own size: reused, never reallocated
};

}  // namespace

std::unique_ptr<pipeline::Stage> makeRefineStage(std::shared_ptr<const RefinerModel> model) {
    if (!model) {
        return pipeline::notAvailable(
            "refine", "no landmark refiner given (Models::loadDefault() reads " + RefinerModel::defaultPath() + " when it exists)");
    }
    return std::make_unique<RefineStage>(std::move(model));
}

}  // namespace facetrack::refine
