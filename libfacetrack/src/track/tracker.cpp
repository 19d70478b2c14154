#include "facetrack/tracker.hpp"

#include "calibration/calibration_stage.hpp"
#include "core/camera.hpp"
#include "core/environment.hpp"
#include "expression/cnn_stage.hpp"
#include "facetrack/error.hpp"
#include "filter/filter_stage.hpp"
#include "fit/fit_stage.hpp"
#include "gaze/gaze_stage.hpp"
#include "landmarks/landmarks_stage.hpp"
#include "landmarks/lbf.hpp"
#include "refine/refine_stage.hpp"
#include "track/tracker_core.hpp"

#include <filesystem>

namespace facetrack {

namespace {
/// The model at `Model::defaultPath()`, or null (logged) when no file is there.
template <class Model>
std::shared_ptr<const Model> loadIfPresent(const char* what, const char* stages) {
    const std::string path = Model::defaultPath();
    std::error_code ec;
    if (std::filesystem::exists(path, ec)) return Model::load(path);
    core::log(std::string(what) + " " + path + " not found: the " + stages + " not available");
    return nullptr;
}
}  // namespace

Models Models::loadDefault() {
    Models models;
    models.face = FaceModel::loadDefault();
    models.landmarks = loadIfPresent<LandmarkModel>("landmark model", "landmarks stage is");
    models.eyes = loadIfPresent<EyeModel>("eye model", "gaze stage is");
    models.refiner = loadIfPresent<RefinerModel>("landmark refiner", "refine stage is");
    models.cnn = loadIfPresent<CnnModel>("CNN file", "cnn stage is");
    return models;
}

void validate(const TrackerConfig& config) {
    if (config.max_faces < 1) throw Error("TrackerConfig::max_faces must be at least 1");
    if (config.detect_interval < 1) throw Error("TrackerConfig::detect_interval must be at least 1");
    if (config.verify_interval < 0 || config.calibration_frames < 0) {
        throw Error("TrackerConfig::verify_interval and calibration_frames must not be negative");
    }
    if (!(config.max_fit_residual > 0.f)) throw Error("TrackerConfig::max_fit_residual must be positive");
    if (!(config.expression_prior > 0.f && config.expression_prior <= 100.f)) {
        throw Error("TrackerConfig::expression_prior must be in (0, 100]");
    }
    landmarks::checkStartCount(config.landmark_starts, "TrackerConfig::landmark_starts");
    const FilterConfig& f = config.filter;
    if (!(f.min_cutoff_hz > 0.0) || !(f.beta >= 0.0) || !(f.derivative_cutoff_hz > 0.0)) {
        throw Error("TrackerConfig::filter: cutoffs must be positive and beta not negative");
    }
    const CameraConfig& c = config.camera;
    core::cameraFor(640, 480, c.horizontal_fov_deg, c.focal_length_px, c.principal_x_px, c.principal_y_px);  // validates
}

namespace {

void validate(const Models& models, const TrackerConfig& config) {
    if (!models.face) throw Error("Tracker: no face model given");
    validate(config);
}

/// The stage list: the order of execution, of stages() and of the timings.
/// Each stage declares what it reads and writes (pipeline::Contract); the
/// TrackerCore checks that every read is written by an earlier stage.
pipeline::StageList stageList(const Models& models, const TrackerConfig& config, const FaceDetector& detector) {
    const FilterConfig& f = config.filter;
    pipeline::StageList stages;
    stages.push_back(landmarks::makeLandmarksStage(models.landmarks, detector.kind(), config.landmark_starts));
    stages.push_back(refine::makeRefineStage(models.refiner));
    stages.push_back(fit::makeFitStage(models.face, {config.max_fit_residual, config.calibration_frames, config.expression_prior}));
    stages.push_back(config.cnn_stage ? expression::makeCnnStage(models.cnn, models.face)
                                      : pipeline::notAvailable("cnn", "off (TrackerConfig::cnn_stage)"));
    stages.push_back(gaze::makeGazeStage(models.eyes, models.face));
    stages.push_back(filter::makeFilterStage(models.face, {f.min_cutoff_hz, f.beta, f.derivative_cutoff_hz}, f.enabled));
    stages.push_back(calibration::makeCalibrationStage(models.face));
    return stages;
}

}  // namespace

struct Tracker::Impl {
    Models models;
    track::TrackerCore core;
    Calibration calibration;
};

Tracker::Tracker(Models models, const TrackerConfig& config) : Tracker(models, config, createFaceDetector(config.detector)) {}

Tracker::Tracker(Models models, const TrackerConfig& config, std::unique_ptr<FaceDetector> detector) {
    validate(models, config);
    if (!detector) throw Error("Tracker: no face detector given");
    pipeline::StageList stages = stageList(models, config, *detector);
    track::LifecycleSettings lifecycle{config.max_faces, config.detect_interval, config.verify_interval, config.camera};
    impl_ = std::make_unique<Impl>(
        Impl{std::move(models), track::TrackerCore(std::move(detector), std::move(stages), std::move(lifecycle)), Calibration{}});
}

Tracker::~Tracker() = default;
Tracker::Tracker(Tracker&&) noexcept = default;
Tracker& Tracker::operator=(Tracker&&) noexcept = default;

FrameResult& Tracker::process(const ImageView& frame, double time_s, FrameResult& out) {
    impl_->core.process(frame, time_s, nullptr, out);
    return out;
}

FrameResult& Tracker::process(const ImageView& frame, double time_s, const std::vector<Box>& faces, FrameResult& out) {
    impl_->core.process(frame, time_s, &faces, out);
    return out;
}

FrameResult Tracker::process(const ImageView& frame, double time_s) {
    FrameResult out;
    impl_->core.process(frame, time_s, nullptr, out);
    return out;
}

void Tracker::reset() { impl_->core.reset(); }
void Tracker::resetIdentity() {
    impl_->calibration.identity.clear();
    impl_->core.setCalibration(impl_->calibration);
    impl_->core.resetIdentity();
}

Calibration Tracker::calibration() const {
    Calibration out = impl_->calibration;
    const FaceResult* face = impl_->core.firstFace();
    if (out.identity.empty() && face && face->identity_calibrated) out.identity = face->identity;
    return out;
}

void validate(const Calibration& calibration, const FaceModel& face) {
    validate(calibration);
    if (!calibration.native_neutral.empty() && calibration.native_neutral.size() != face.expressionNames().size()) {
        throw Error("calibration: native_neutral has " + std::to_string(calibration.native_neutral.size()) + " weights, the face model " +
                    std::to_string(face.expressionNames().size()));
    }
    if (!calibration.identity.empty() && static_cast<int>(calibration.identity.size()) != face.identityCount()) {
        throw Error("calibration: identity has " + std::to_string(calibration.identity.size()) + " coefficients, the face model " +
                    std::to_string(face.identityCount()));
    }
}

void Tracker::setCalibration(const Calibration& calibration) {
    validate(calibration, *impl_->models.face);
    impl_->core.setCalibration(calibration);
    impl_->calibration = calibration;
}

void Tracker::calibrateNeutral() {
    Calibration next = impl_->calibration;
    if (impl_->core.captureNeutral(next)) setCalibration(next);
}

void Tracker::resetNeutral() {
    Calibration next = impl_->calibration;
    for (auto& shape : next.shapes) shape.neutral = 0.f;
    next.native_neutral.clear();
    setCalibration(next);
}

std::vector<StageInfo> Tracker::stages() const { return impl_->core.stages(); }

std::vector<std::string> Tracker::estimatedShapes() const {
    const FaceModel& face = *impl_->models.face;
    std::vector<float> native(face.expressionNames().size(), 0.f);
    for (const int k : impl_->core.estimatedExpressions()) native[static_cast<std::size_t>(k)] = 1.f;
    const auto arkit = face.toArkit(native);
    std::vector<std::string> names;
    for (std::size_t i = 0; i < arkit.size(); ++i)
        if (arkit[i] > 0.f) names.emplace_back(arkitNames()[i]);
    return names;
}
const Models& Tracker::models() const { return impl_->models; }

}  // namespace facetrack
