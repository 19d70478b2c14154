#include "expression/cnn_stage.hpp"

#include "core/shape2d.hpp"
#include "expression/geometry_net.hpp"
#include "expression/landmark_net.hpp"
#include "expression/lip_net.hpp"
#include "expression/update_net.hpp"
#include "facetrack/error.hpp"
#include "fit/fit_basis.hpp"
#include "model/internals.hpp"
#include "nn/cnn_model_data.hpp"

#include <algorithm>
#include <optional>

namespace facetrack::expression {

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
    CnnStage(std::shared_ptr<const CnnModel> cascade, std::shared_ptr<const FaceModel> face)
        : cascade_(std::move(cascade)), face_(std::move(face)) {
        const nn::CnnModelData& d = model::dataOf(*cascade_);
        layout_ = makeWarpLayout(model::dataOf(*face_), nn::expressionIndices(face_->expressionNames(), d.expressions), d.patch_size);
        if (d.mirror_averaged) mirror_ = updateMirror(d.expressions);
        for (std::size_t i = 0; i < d.stages.size(); ++i) {
            nets_.emplace_back(d.stages[i].onnx, d.patch_size, 6 + static_cast<int>(d.expressions.size()),
                               "CNN cascade '" + cascade_->sourcePath() + "' stage " + std::to_string(i + 1), mirror_ ? 2 : 1);
        }
        if (!d.geometry_net.empty()) geometry_net_.emplace(d.geometry_net, d.expressions);
        if (!d.lip_net.empty())
            lip_net_.emplace(d.lip_net, d.lip_patch_size, d.lip_patch_half, "CNN cascade '" + cascade_->sourcePath() + "' lip net");
        if (cascade_->hasLandmarkNet()) {
            landmark_basis_ = landmarkBasis(*face_, layout_.anchors.expressions);
            landmark_net_.emplace(d.landmark_net, d.patch_size, kLandmarkOutputs,
                                  "CNN cascade '" + cascade_->sourcePath() + "' landmark net");
        }
    }

    StageInfo info() const override {
        std::string rounds;
        for (const int r : cascade_->rounds()) {
            if (!rounds.empty()) rounds += '+';
            rounds += std::to_string(r);
        }
        return {"cnn", true,
                std::string(cascade_->expressionsOnly()
                                ? "expressions only (" + std::to_string(readCount()) +
                                      (model::dataOf(*cascade_).corrects_fit ? ", the fit's corrected" : " beside the fit's") + "), "
                                : "") +
                    std::to_string(nets_.size()) + " stage(s), " + rounds + " rounds, " + std::to_string(layout_.size) + " px patch, " +
                    std::to_string(layout_.anchors.expressions.size()) + " expressions" + (mirror_ ? ", mirror-averaged" : "") +
                    (geometry_net_ ? ", " + std::to_string(geometryCount()) + " read from the landmarks' geometry" +
                                         (lip_net_ ? " and the lip net's points" : "")
                                   : "") +
                    (landmark_net_ ? ", landmark net" : "") + "; nets on the " + nets_.front().engineName() + " (" +
                    cascade_->sourcePath() + ")"};
    }

    std::unique_ptr<pipeline::StageState> newFaceState() const override {
        auto s = std::make_unique<CnnFaceState>();
        s->params.expression = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(layout_.anchors.expressions.size()));
        s->identity.reserve(static_cast<std::size_t>(face_->identityCount()));
        return s;
    }

    pipeline::Contract contract() const override {
        using pipeline::Field;
        pipeline::Contract c{Field::Pose | Field::Expression | Field::Identity, Field::Expression};
        if (geometry_net_) c.reads = c.reads | Field::Landmarks;
        if (!cascade_->expressionsOnly()) c.writes = c.writes | Field::Pose;
        if (landmark_net_) c.writes = c.writes | Field::Landmarks;
        for (const Reported& r : reported_) c.expressions.push_back(layout_.anchors.expressions[static_cast<std::size_t>(r.position)]);
        return c;
    }

    /// The expressions an earlier stage estimates (the fit's) are the ones an
    /// expressions-only cascade leaves alone, or corrects.
    void connect(const pipeline::Upstream& upstream) override {
        const nn::CnnModelData& d = model::dataOf(*cascade_);
        reported_.clear();
        for (std::size_t k = 0; k < layout_.anchors.expressions.size(); ++k) {
            const int e = layout_.anchors.expressions[k];
            const bool fitted = std::find(upstream.expressions.begin(), upstream.expressions.end(), e) != upstream.expressions.end();
            const bool read = d.reported.empty() || d.reported[k] || (geometry_net_ && d.geometry_reported[k]);
            if (!d.expressions_only || (read && (!fitted || d.corrects_fit)))
                reported_.push_back({static_cast<int>(k), !fitted || d.corrects_fit});
        }
    }

    pipeline::Outcome run(const pipeline::FrameInput& frame, pipeline::FaceTrack& face, pipeline::StageState* state) override {
        using pipeline::Outcome;
        auto& s = static_cast<CnnFaceState&>(*state);
        FaceResult& r = face.result;
        if (!r.pose || !r.expression) return Outcome::Ok;  // nothing fitted to refine
        if (!s.shaped || s.identity != r.identity) {
            s.identity = r.identity;
            Eigen::VectorXd a = Eigen::VectorXd::Zero(layout_.anchors.identityCount());
            for (std::size_t k = 0; k < s.identity.size() && k < static_cast<std::size_t>(a.size()); ++k)
                a[static_cast<Eigen::Index>(k)] = s.identity[k];
            s.work.identity_shape = fit::shapeWithIdentity(layout_.anchors, a);
            if (landmark_net_) s.landmark_identity_shape = fit::shapeWithIdentity(landmark_basis_, a);
            s.shaped = true;
        }
        readParams(*r.pose, r.expression->native, layout_.anchors.expressions, s.params);
        const auto& stages = model::dataOf(*cascade_).stages;
        for (std::size_t i = 0; i < nets_.size(); ++i) {
            if (!refine(layout_, nets_[i], frame.gray, frame.camera, s.params, stages[i].rounds, s.work, mirror_ ? &*mirror_ : nullptr)) {
                return Outcome::Ok;  // keep the fit's answer
            }
        }
        if (!cascade_->expressionsOnly()) r.pose = fit::headPoseOf(s.params);
        std::vector<float>& native = r.expression->native;
        const std::vector<float>& neutral = model::dataOf(*cascade_).neutral;
        const std::vector<float>& full = model::dataOf(*cascade_).full;
        for (const auto& [k, neutralised] : reported_) {
            float w = static_cast<float>(s.params.expression[k]);
            if (!neutral.empty() && neutralised) {
                const auto i = static_cast<std::size_t>(k);
                w = std::clamp((w - neutral[i]) / ((full.empty() ? 1.f : full[i]) - neutral[i]), 0.f, 1.f);
            }
            native[static_cast<std::size_t>(layout_.anchors.expressions[static_cast<std::size_t>(k)])] = w;
        }
        if (geometry_net_ && r.landmarks) readGeometry(frame.gray, *r.landmarks, r.pose->euler_deg, native);
        r.expression->arkit = face_->toArkit(native);
        if (landmark_net_) moveLandmarks(frame, face, s);
        return Outcome::Ok;
    }

private:
    /// How many expressions the file reads (info() comes before connect() drops those an earlier stage owns).
    int readCount() const {
        const nn::CnnModelData& d = model::dataOf(*cascade_);
        int n = 0;
        for (std::size_t k = 0; k < d.expressions.size(); ++k)
            n += d.reported.empty() || d.reported[k] || (geometry_net_ && d.geometry_reported[k]);
        return n;
    }
    int geometryCount() const {
        const auto& g = model::dataOf(*cascade_).geometry_reported;
        return static_cast<int>(std::count(g.begin(), g.end(), true));
    }

    /// The geometry net's readings (geometry_net.hpp; with the lip net's points, lip_net.hpp) in
    /// place of the texture's, for the expressions the file reads from the geometry, each between
    /// its own neutral and full readings.
    void readGeometry(const cv::Mat& gray, const Landmarks68& landmarks, const Vec3& eulerDeg, std::vector<float>& native) {
        const nn::CnnModelData& d = model::dataOf(*cascade_);
        const core::Shape68 points = core::fromLandmarks68(landmarks);
        const LipPoints* lips = lip_net_ ? &lip_net_->predict(gray, points) : nullptr;
        if (lips && !lips->allFinite()) return;
        const Eigen::VectorXf& g = geometry_net_->predict(points, eulerDeg.x, eulerDeg.y, lips);
        if (!g.allFinite()) return;
        for (const Reported& r : reported_) {
            const auto k = static_cast<std::size_t>(r.position);
            if (!d.geometry_reported[k]) continue;
            const float w = std::clamp((g[r.position] - d.geometry_neutral[k]) / (d.geometry_full[k] - d.geometry_neutral[k]), 0.f, 1.f);
            native[static_cast<std::size_t>(layout_.anchors.expressions[k])] = w;
        }
    }

    /// The landmark net's landmarks (landmark_net.hpp) at the refined parameters, in place of the
    /// landmark stage's; kept when a value is not finite.
    void moveLandmarks(const pipeline::FrameInput& frame, pipeline::FaceTrack& face, CnnFaceState& s) {
        projectAnchors(layout_, s.work.identity_shape, frame.camera, s.params, s.work.anchors3d, s.work.anchors);
        if (!s.work.anchors.allFinite()) return;
        warpFace(layout_, frame.gray, s.work.anchors, s.work.patch);
        const fit::Landmarks2d q = displaced(
            patchToFrame(layout_, s.work.anchors),
            projectedLandmarks(landmark_basis_, s.landmark_identity_shape, frame.camera, s.params, s.landmark_slots),
            landmark_net_->predict(s.work.patch));
        if (!q.allFinite()) return;
        const core::Shape68 moved = q.cast<float>();
        face.result.landmarks = core::toLandmarks68(moved);
        face.locate(core::boundsOf(moved));
    }

    std::shared_ptr<const CnnModel> cascade_;
    std::shared_ptr<const FaceModel> face_;
    WarpLayout layout_;
    std::vector<nn::PatchNet> nets_;
    fit::FitBasis landmark_basis_;
    std::optional<nn::PatchNet> landmark_net_;
    std::optional<UpdateMirror> mirror_;
    std::optional<GeometryNet> geometry_net_;
    std::optional<LipNet> lip_net_;
    struct Reported {
        int position;  ///< in the layout's expressions
        /// Read between its neutral and full readings: a reading, or a correction of the fit's
        /// by a net that reads every shape it reports (corrects_fit).
        bool neutralised;
    };
    std::vector<Reported> reported_;  ///< the expressions this stage writes
};

}  // namespace

std::unique_ptr<pipeline::Stage> makeCnnStage(std::shared_ptr<const CnnModel> cascade, std::shared_ptr<const FaceModel> face) {
    if (!cascade) {
        return pipeline::notAvailable("cnn",
                                      "no CNN file given (Models::loadDefault() reads " + CnnModel::defaultPath() + " when it exists)");
    }
    return std::make_unique<CnnStage>(std::move(cascade), std::move(face));
}

}  // namespace facetrack::expression
