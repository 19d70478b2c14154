#include "fit/fit_stage.hpp"

#include "core/math.hpp"
#include "fit/face_fitter.hpp"

#include "facetrack/error.hpp"

#include <algorithm>
#include <cmath>

namespace facetrack::fit {

namespace {

// Beyond these the fitted face is not a face in front of a webcam.
constexpr double kMaxPitchDeg = 70.0, kMaxYawDeg = 80.0;
constexpr double kMinDepthCm = 10.0, kMaxDepthCm = 1000.0;
constexpr int kCalibrationStride = 5;  // frames between identity calibration samples
// A head turning this much between two frames (300 deg/s at 30 fps) is more
// likely a fit that slid off the face: on the clips, followed faces turn at
// most ~6 deg a frame.
constexpr double kDoubtfulTurnDeg = 10.0;
// A warm fit that turned this far started from the previous frame's pose (its
// landmarks' start, its jaw contour) and may have stopped short: the stages run
// again from where it ended. From a start 15 deg away (eval_cnn --tracker) the
// answer lands within 3 deg of an unperturbed start's on 94 % of validation
// faces (10 deg: 91 %; none: 84 %); 31 of the ten clips' 4,651 frames turn this far.
constexpr double kUnsettledTurnDeg = 5.0;
// A fit this close to losing the face is checked too (d12, glasses and fast
// moves: residual median 0.4, p95 0.6 of max_residual; other clips below 0.5).
constexpr double kDoubtfulResidualShare = 0.75;

struct FitFaceState final : pipeline::StageState {
    FitFaceState(const std::shared_ptr<const FitBasis>& basis, const FitSettings& fitSettings, int calibrationFrames)
        : fitter(basis, fitSettings), window(static_cast<std::size_t>(calibrationFrames)) {
        // Sized up front, so that taking a sample copies into place.
        for (auto& frame : window) frame.params.expression = Eigen::VectorXd::Zero(basis->expressionCount());
    }
    FaceFitter fitter;
    FaceParams params;
    bool fitted = false;
    std::vector<CalibrationFrame> window;  // identity calibration samples, the first `samples` taken
    std::size_t samples = 0;
    int sampled_age = -1;  // a frame the tracker runs twice (doubtful or unsettled) is sampled once
    bool calibrated = false;
};

class FitStage final : public pipeline::Stage {
public:
    FitStage(std::shared_ptr<const FaceModel> model, const FitStageSettings& settings)
        : model_(std::move(model)), basis_(basisOf(model_)), settings_(settings) {}

    StageInfo info() const override {
        return {"fit", true,
                "Ceres: pose, " + std::to_string(basis_->expressionCount()) + " expressions, " + std::to_string(basis_->identityCount()) +
                    " identity modes" +
                    (settings_.calibration_frames > 0 ? ", identity from " + std::to_string(settings_.calibration_frames) + " frames"
                                                      : ", mean identity")};
    }

    std::unique_ptr<pipeline::StageState> newFaceState() const override {
        FitSettings fitSettings;
        fitSettings.expression_l2 *= settings_.expression_prior;
        auto state = std::make_unique<FitFaceState>(basis_, fitSettings, settings_.calibration_frames);
        if (identity_.size() > 0) adoptIdentity(*state);
        return state;
    }

    pipeline::Contract contract() const override {
        using pipeline::Field;
        return {Field::Landmarks, Field::Pose | Field::Expression | Field::Identity | Field::Fit | Field::NextStart, basis_->expressions};
    }

    pipeline::Outcome run(const pipeline::FrameInput& frame, pipeline::FaceTrack& face, pipeline::StageState* state) override {
        using pipeline::Outcome;
        auto& s = static_cast<FitFaceState&>(*state);
        if (!face.result.landmarks) return Outcome::Lost;
        Landmarks2d observed;
        for (int i = 0; i < model::kLandmarkCount; ++i) observed.col(i) << (*face.result.landmarks)[i].x, (*face.result.landmarks)[i].y;
        // A face found again (fresh) starts cold: the previous pose may be the one that slid off it.
        const bool warm = s.fitted && !face.fresh;
        const Eigen::Matrix3d before = rotationOf(s.params.omega());
        const FitReport report = s.fitter.fit(frame.camera, observed, s.params, warm);
        s.fitted = true;
        const Eigen::Vector3d euler = eulerDegrees(s.params.omega());
        const double depth = s.params.translation().z();
        if (!(report.residual <= settings_.max_residual) || std::abs(euler.x()) > kMaxPitchDeg || std::abs(euler.y()) > kMaxYawDeg ||
            !(depth >= kMinDepthCm && depth <= kMaxDepthCm)) {
            return Outcome::Lost;
        }
        const double turnDeg = Eigen::AngleAxisd(rotationOf(s.params.omega()) * before.transpose()).angle() / core::kRadiansPerDegree;
        const bool doubtful = report.residual > kDoubtfulResidualShare * settings_.max_residual || (warm && turnDeg > kDoubtfulTurnDeg);
        const bool unsettled = warm && turnDeg > kUnsettledTurnDeg;
        sampleForCalibration(frame, face, s, observed, report);
        writeResult(face, s, report);
        return doubtful ? Outcome::Doubtful : unsettled ? Outcome::Unsettled : Outcome::Ok;
    }

    void resetIdentity(pipeline::StageState* state) const override {
        auto& s = static_cast<FitFaceState&>(*state);
        s.fitter.setIdentity({});
        s.calibrated = false;
        s.samples = 0;
    }

    /// A calibration's identity is the user's: every face takes it, calibrated.
    void setCalibration(const Calibration& calibration, const std::vector<pipeline::StageState*>& faces) override {
        if (!calibration.identity.empty() && static_cast<int>(calibration.identity.size()) != basis_->identityCount()) {
            throw Error("calibration: identity has " + std::to_string(calibration.identity.size()) + " coefficients, the face model " +
                        std::to_string(basis_->identityCount()));
        }
        identity_.resize(0);
        if (calibration.identity.empty()) return;  // none given: new faces estimate their own, followed ones keep theirs
        identity_ = Eigen::Map<const Eigen::VectorXf>(calibration.identity.data(), basis_->identityCount()).cast<double>();
        for (pipeline::StageState* face : faces) adoptIdentity(static_cast<FitFaceState&>(*face));
    }

private:
    void adoptIdentity(FitFaceState& s) const {
        s.fitter.setIdentity(identity_);
        s.calibrated = true;
        s.samples = 0;
    }

    /// Every kCalibrationStride-th well-fitted frame joins the window; a full
    /// window gives the identity, fitted jointly with every sample's pose and
    /// expression, then frozen.
    void sampleForCalibration(const pipeline::FrameInput& frame, const pipeline::FaceTrack& face, FitFaceState& s,
                              const Landmarks2d& observed, const FitReport& report) const {
        if (s.calibrated || s.window.empty() || face.age % kCalibrationStride != 0 || face.age == s.sampled_age ||
            report.residual > 0.5 * settings_.max_residual) {
            return;
        }
        s.sampled_age = face.age;
        CalibrationFrame& sample = s.window[s.samples++];
        sample.camera = frame.camera;
        sample.observed = observed;
        sample.params.pose = s.params.pose;
        sample.params.expression = s.params.expression;
        sample.contour = report.contour;
        if (s.samples < s.window.size()) return;
        s.fitter.setIdentity(calibrateIdentity(*basis_, s.window, s.fitter.settings()));
        s.calibrated = true;
        s.samples = 0;
    }

    void writeResult(pipeline::FaceTrack& face, const FitFaceState& s, const FitReport& report) const {
        FaceResult& r = face.result;
        r.fit_residual = static_cast<float>(report.residual);
        r.confidence = std::clamp(1.f - static_cast<float>(report.residual) / settings_.max_residual, 0.f, 1.f);
        r.pose = headPoseOf(s.params);
        if (!r.expression) r.expression.emplace();
        std::vector<float>& native = r.expression->native;
        native.assign(static_cast<std::size_t>(basis_->native_expression_count), 0.f);
        for (int k = 0; k < basis_->expressionCount(); ++k) {
            native[basis_->expressions[k]] = static_cast<float>(std::clamp(s.params.expression[k], 0.0, 1.0));
        }
        r.expression->arkit = model_->toArkit(native);
        const Eigen::VectorXd& identity = s.fitter.identity();
        r.identity.resize(static_cast<std::size_t>(identity.size()));
        for (Eigen::Index k = 0; k < identity.size(); ++k) r.identity[k] = static_cast<float>(identity[k]);
        r.identity_calibrated = s.calibrated;
        if (!face.next_start) face.next_start.emplace();
        for (int i = 0; i < model::kLandmarkCount; ++i) {
            (*face.next_start)[i] = {static_cast<float>(report.projected(0, i)), static_cast<float>(report.projected(1, i))};
        }
    }

    std::shared_ptr<const FaceModel> model_;
    std::shared_ptr<const FitBasis> basis_;
    FitStageSettings settings_;
    Eigen::VectorXd identity_;  ///< the calibration's; empty: each face estimates its own
};

}  // namespace

std::unique_ptr<pipeline::Stage> makeFitStage(std::shared_ptr<const FaceModel> model, const FitStageSettings& settings) {
    return std::make_unique<FitStage>(std::move(model), settings);
}

}  // namespace facetrack::fit
