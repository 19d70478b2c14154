#include "filter/filter_stage.hpp"

#include "core/one_euro.hpp"
#include "core/shape2d.hpp"
#include "fit/pose.hpp"

#include <algorithm>
#include <cstdio>
#include <string>

namespace facetrack::filter {

namespace {

constexpr double kTranslationScaleMm = 90.0;  // ~ an eye-corner distance: the unit of translation speed
/// The landmarks' cutoff also rises with the speed of their centroid, times
/// this factor times beta. The mean of 68 points carries about 1/8 of one
/// point's noise, so it can carry a larger gain than a point's own speed: at
/// the same jitter it lags fast head moves less (docs/benchmarks.md, "The
/// filter on a face that moves").
constexpr double kFaceMotionGain = 5.0;

/// Each expression's rest cutoff, as a factor on the filter's min cutoff: brows move slowly and
/// their estimate is the noisiest, so they are held steadier; the lips and jaw follow speech, so
/// they are let through faster; the rest (cheeks, nose, eye squint) as set. The eye shapes the
/// gaze stage smooths itself (blinks must not lag) pass through.
double minCutoffScale(const std::string& name) {
    for (const char* brow : {"browDown", "browInnerUp", "browOuterUp"})
        if (name.rfind(brow, 0) == 0) return 0.5;
    for (const char* speech : {"jaw", "mouth"})
        if (name.rfind(speech, 0) == 0) return 1.5;
    return 1.0;
}

struct FilterFaceState final : pipeline::StageState {
    explicit FilterFaceState(const core::OneEuroSettings& s)
        : landmarks(s), rotation(s), translation(s), expression(s), face_motion(s.derivative_cutoff_hz) {}
    core::OneEuroFilter landmarks, rotation, translation, expression;
    core::MotionSpeed face_motion;                                      // of the landmarks' centroid
    Eigen::Quaterniond last_rotation = Eigen::Quaterniond::Identity();  // keeps q and -q apart
    // The filters' inputs, sized once.
    Eigen::VectorXd landmark_sample, rotation_sample = Eigen::VectorXd(4), translation_sample = Eigen::VectorXd(3), expression_sample;
};

class FilterStage final : public pipeline::Stage {
public:
    FilterStage(std::shared_ptr<const FaceModel> model, const core::OneEuroSettings& settings, bool enabled)
        : model_(std::move(model)), settings_(settings), enabled_(enabled) {
        if (!model_) return;  // no expressions to filter
        const auto& names = model_->expressionNames();
        expression_cutoff_scale_.resize(static_cast<Eigen::Index>(names.size()));
        for (std::size_t k = 0; k < names.size(); ++k) expression_cutoff_scale_[static_cast<Eigen::Index>(k)] = minCutoffScale(names[k]);
    }

    StageInfo info() const override {
        if (!enabled_) return {"filter", false, "off (TrackerConfig::filter.enabled)"};
        char detail[128];
        std::snprintf(detail, sizeof detail, "1-euro (min cutoff %g Hz, beta %g; brows x0.5, lips and jaw x1.5)", settings_.min_cutoff_hz,
                      settings_.beta);
        return {"filter", true, detail};
    }

    pipeline::Contract contract() const override {
        using pipeline::Field;
        return {{}, Field::Raw | Field::Landmarks | Field::Pose | Field::Expression};
    }

    void connect(const pipeline::Upstream& upstream) override { pass_through_ = upstream.smoothed_expressions; }

    std::unique_ptr<pipeline::StageState> newFaceState() const override {
        auto s = std::make_unique<FilterFaceState>(settings_);
        s->expression.setMinCutoffScale(expression_cutoff_scale_);
        return s;
    }

    pipeline::Outcome run(const pipeline::FrameInput& frame, pipeline::FaceTrack& face, pipeline::StageState* state) override {
        auto& s = static_cast<FilterFaceState&>(*state);
        if (face.fresh) {  // found (again): what the filters hold may be another place
            s.landmarks.reset();
            s.face_motion.reset();
            s.rotation.reset();
            s.translation.reset();
            s.expression.reset();
        }
        FaceResult& r = face.result;
        r.raw.landmarks = r.landmarks;
        r.raw.pose = r.pose;
        r.raw.expression = r.expression;
        if (r.landmarks) filterLandmarks(frame.dt, s, *r.landmarks);
        if (r.pose) filterPose(frame.dt, s, *r.pose);
        if (r.expression) filterExpression(frame.dt, s, *r.expression);
        return pipeline::Outcome::Ok;
    }

private:
    void filterLandmarks(double dt, FilterFaceState& s, Landmarks68& points) const {
        s.landmark_sample.resize(2 * static_cast<Eigen::Index>(points.size()));
        Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
        for (std::size_t i = 0; i < points.size(); ++i) {
            s.landmark_sample.segment<2>(2 * i) << points[i].x, points[i].y;
            centroid += s.landmark_sample.segment<2>(2 * i);
        }
        centroid /= static_cast<double>(points.size());
        const double scale = std::max(1.f, core::eyeCornerDistance(points));
        const double faceMotionHz = kFaceMotionGain * settings_.beta * s.face_motion(centroid, dt, scale);
        const Eigen::VectorXd& smooth = s.landmarks(s.landmark_sample, dt, scale, faceMotionHz);
        for (std::size_t i = 0; i < points.size(); ++i) {
            points[i] = {static_cast<float>(smooth[2 * i]), static_cast<float>(smooth[2 * i + 1])};
        }
    }

    static void filterPose(double dt, FilterFaceState& s, HeadPose& pose) {
        Eigen::Quaterniond q(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z);
        if (q.coeffs().dot(s.last_rotation.coeffs()) < 0.0) q.coeffs() = -q.coeffs();
        s.last_rotation = q;
        s.rotation_sample = q.coeffs();
        const Eigen::Quaterniond smoothRotation(Eigen::Vector4d(s.rotation(s.rotation_sample, dt, 1.0)));
        s.translation_sample << pose.translation_mm.x, pose.translation_mm.y, pose.translation_mm.z;
        const Eigen::Vector3d smoothTranslation = s.translation(s.translation_sample, dt, kTranslationScaleMm);
        pose = fit::headPoseOf(smoothRotation, smoothTranslation);
    }

    void filterExpression(double dt, FilterFaceState& s, ExpressionResult& e) const {
        s.expression_sample.resize(static_cast<Eigen::Index>(e.native.size()));
        for (std::size_t k = 0; k < e.native.size(); ++k) s.expression_sample[k] = e.native[k];
        const Eigen::VectorXd& smooth = s.expression(s.expression_sample, dt, 1.0);
        for (std::size_t k = 0; k < e.native.size(); ++k) e.native[k] = static_cast<float>(std::clamp(smooth[k], 0.0, 1.0));
        for (const int k : pass_through_) {
            if (static_cast<std::size_t>(k) < e.native.size())
                e.native[static_cast<std::size_t>(k)] = static_cast<float>(s.expression_sample[k]);
        }
        e.arkit = model_->toArkit(e.native);
    }

    std::shared_ptr<const FaceModel> model_;
    core::OneEuroSettings settings_;
    bool enabled_;
    std::vector<int> pass_through_;            // native expressions smoothed by an earlier stage
    Eigen::VectorXd expression_cutoff_scale_;  // per native expression, minCutoffScale()
};

}  // namespace

std::unique_ptr<pipeline::Stage> makeFilterStage(std::shared_ptr<const FaceModel> model, const core::OneEuroSettings& settings,
                                                 bool enabled) {
    return std::make_unique<FilterStage>(std::move(model), settings, enabled);
}

}  // namespace facetrack::filter
