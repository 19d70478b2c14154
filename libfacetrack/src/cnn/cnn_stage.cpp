#include "cnn/cnn_stage.hpp"

#include "cnn/cnn_model_data.hpp"
#include "cnn/landmark_net.hpp"
#include "cnn/update_net.hpp"
#include "facetrack/error.hpp"
#include "fit/fit_basis.hpp"
#include "landmarks/lbf.hpp"

#include <algorithm>
#include <optional>

namespace facetrack::cnn {

namespace {

struct CnnFaceState final : pipeline::StageState {
    fit::FaceParams params;
    std::vector<float> identity;  ///< the identity work.identity_shape is of
    bool shaped = false;
    RefineWork work;
    Eigen::Matrix3Xd landmark_identity_shape, landmark_slots;  ///< of the landmark basis
};

class CnnStage final : public pipeline::Stage {
public:
    CnnStage(std::shared_ptr<const CnnModel> cascade, std::shared_ptr<const FaceModel> face, const std::vector<int>& fitExpressions)
        : cascade_(std::move(cascade)), face_(std::move(face)) {
        const CnnModelData& d = cascade_->data();
        layout_ = makeWarpLayout(face_->data(), expressionIndices(face_->expressionNames(), d.expressions), d.patch_size);
        for (std::size_t k = 0; k < layout_.anchors.expressions.size(); ++k) {
            const int e = layout_.anchors.expressions[k];
            const bool fitted = std::find(fitExpressions.begin(), fitExpressions.end(), e) != fitExpressions.end();
            const bool read = d.reported.empty() || d.reported[k];
            if (!d.expressions_only || (read && (!fitted || d.corrects_fit))) reported_.push_back({static_cast<int>(k), !fitted});
        }
        if (d.mirror_averaged) mirror_ = updateMirror(d.expressions);
        for (std::size_t i = 0; i < d.stages.size(); ++i) {
            nets_.emplace_back(d.stages[i].onnx, d.patch_size, 6 + static_cast<int>(d.expressions.size()),
                               "CNN cascade '" + cascade_->sourcePath() + "' stage " + std::to_string(i + 1), mirror_ ? 2 : 1);
        }
        if (cascade_->hasLandmarkNet()) {
            landmark_basis_ = landmarkBasis(*face_, layout_.anchors.expressions);
            landmark_net_.emplace(d.landmark_net, d.patch_size, kLandmarkOutputs, "CNN cascade '" + cascade_->sourcePath() + "' landmark net");
        }
    }

    StageInfo info() const override {
        std::string rounds;
        for (const int r : cascade_->rounds()) {
            if (!rounds.empty()) rounds += '+';
            rounds += std::to_string(r);
        }
        return {"cnn", true,
                std::string(cascade_->expressionsOnly() ? "expressions only (" + std::to_string(reported_.size()) +
                                (cascade_->data().corrects_fit ? ", the fit's corrected" : " beside the fit's") + "), " : "") +
                    std::to_string(nets_.size()) + " stage(s), " + rounds + " rounds, " + std::to_string(layout_.size) + " px patch, " +
                    std::to_string(layout_.anchors.expressions.size()) + " expressions" + (mirror_ ? ", mirror-averaged" : "") +
                    (landmark_net_ ? ", landmark net" : "") +
                    "; nets on the " + nets_.front().engineName() + " (" +
                    cascade_->sourcePath() + ")"};
    }

    std::unique_ptr<pipeline::StageState> newFaceState() const override {
        auto s = std::make_unique<CnnFaceState>();
        s->params.expression = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(layout_.anchors.expressions.size()));
        s->identity.reserve(static_cast<std::size_t>(face_->identityCount()));
        return s;
    }

    std::vector<int> estimatedExpressions() const override {
        std::vector<int> out;
        for (const Reported& r : reported_) out.push_back(layout_.anchors.expressions[static_cast<std::size_t>(r.position)]);
        return out;
    }

    bool run(const pipeline::FrameInput& frame, pipeline::FaceTrack& face, pipeline::StageState* state) override {
        auto& s = static_cast<CnnFaceState&>(*state);
        FaceResult& r = face.result;
        if (!r.pose || !r.expression) return true;  // nothing fitted to refine
        if (!s.shaped || s.identity != r.identity) {
            s.identity = r.identity;
            Eigen::VectorXd a = Eigen::VectorXd::Zero(layout_.anchors.identityCount());
            for (std::size_t k = 0; k < s.identity.size() && k < static_cast<std::size_t>(a.size()); ++k) a[static_cast<Eigen::Index>(k)] = s.identity[k];
            s.work.identity_shape = fit::shapeWithIdentity(layout_.anchors, a);
            if (landmark_net_) s.landmark_identity_shape = fit::shapeWithIdentity(landmark_basis_, a);
            s.shaped = true;
        }
        readParams(*r.pose, r.expression->native, layout_.anchors.expressions, s.params);
        const auto& stages = cascade_->data().stages;
        for (std::size_t i = 0; i < nets_.size(); ++i) {
            if (!refine(layout_, nets_[i], frame.gray, frame.camera, s.params, stages[i].rounds, s.work, mirror_ ? &*mirror_ : nullptr)) {
                return true;  // keep the fit's answer
            }
        }
        if (!cascade_->expressionsOnly()) r.pose = fit::headPoseOf(s.params);
        std::vector<float>& native = r.expression->native;
        const std::vector<float>& neutral = cascade_->data().neutral;
        for (const auto& [k, neutralised] : reported_) {
            float w = static_cast<float>(s.params.expression[k]);
            if (!neutral.empty() && neutralised) {
                w = std::clamp((w - neutral[static_cast<std::size_t>(k)]) / (1.f - neutral[static_cast<std::size_t>(k)]), 0.f, 1.f);
            }
            native[static_cast<std::size_t>(layout_.anchors.expressions[static_cast<std::size_t>(k)])] = w;
        }
        r.expression->arkit = face_->toArkit(native);
        if (landmark_net_) moveLandmarks(frame, face, s);
        return true;
    }

private:
    /// The landmark net's landmarks (landmark_net.hpp) at the refined parameters, in place of the
    /// landmark stage's; kept when a value is not finite.
    void moveLandmarks(const pipeline::FrameInput& frame, pipeline::FaceTrack& face, CnnFaceState& s) {
        projectAnchors(layout_, s.work.identity_shape, frame.camera, s.params, s.work.anchors3d, s.work.anchors);
        if (!s.work.anchors.allFinite()) return;
        warpFace(layout_, frame.gray, s.work.anchors, s.work.patch);
        const fit::Landmarks2d q = displaced(patchToFrame(layout_, s.work.anchors),
                                             projectedLandmarks(landmark_basis_, s.landmark_identity_shape, frame.camera, s.params, s.landmark_slots),
                                             landmark_net_->predict(s.work.patch));
        if (!q.allFinite()) return;
        const landmarks::Shape68 moved = q.cast<float>();
        face.result.landmarks = landmarks::toLandmarks68(moved);
        face.locate(landmarks::boundsOf(moved));
    }

    std::shared_ptr<const CnnModel> cascade_;
    std::shared_ptr<const FaceModel> face_;
    WarpLayout layout_;
    std::vector<PatchNet> nets_;
    fit::FitBasis landmark_basis_;
    std::optional<PatchNet> landmark_net_;
    std::optional<UpdateMirror> mirror_;
    struct Reported {
        int position;      ///< in the layout's expressions
        bool neutralised;  ///< a reading the neutral applies to, not a correction of the fit's
    };
    std::vector<Reported> reported_;  ///< the expressions this stage writes
};

}  // namespace

std::unique_ptr<pipeline::Stage> makeCnnStage(std::shared_ptr<const CnnModel> cascade, std::shared_ptr<const FaceModel> face,
                                              const pipeline::Stage* fit) {
    if (!cascade) {
        return pipeline::notAvailable("cnn",
                                      "no CNN file given (Models::loadDefault() reads " + CnnModel::defaultPath() + " when it exists)");
    }
    if (!fit || !fit->info().available) return pipeline::notAvailable("cnn", "needs the fit stage's pose and expressions");
    if (!cascade->hasCascade()) return pipeline::notAvailable("cnn", "'" + cascade->sourcePath() + "' has no cascade stages");
    return std::make_unique<CnnStage>(std::move(cascade), std::move(face), fit->estimatedExpressions());
}

}  // namespace facetrack::cnn
