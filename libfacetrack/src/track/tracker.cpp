#include "facetrack/tracker.hpp"

#include "core/environment.hpp"
#include "core/image.hpp"
#include "facetrack/error.hpp"
#include "facetrack/version.hpp"
#include "fit/camera.hpp"
#include "landmarks/lbf.hpp"
#include "track/face_track.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <filesystem>

namespace facetrack {

namespace {

/// Per-stage wall-clock times of one frame, summed over faces, in pipeline order.
class StageTimes {
public:
    template <class Stage>
    auto run(const char* name, Stage&& stage) {
        const auto start = std::chrono::steady_clock::now();
        struct Add {
            StageTimes* self;
            const char* name;
            std::chrono::steady_clock::time_point start;
            ~Add() { self->add(name, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count()); }
        } add{this, name, start};
        return stage();
    }
    std::vector<StageTiming> inPipelineOrder() const {
        static const char* const kOrder[] = {"detect", "landmarks", "fit", "calibrate", "verify", "filter"};
        std::vector<StageTiming> out;
        for (const char* stage : kOrder) {
            for (const auto& t : times_) {
                if (t.stage == stage) out.push_back(t);
            }
        }
        return out;
    }

private:
    void add(const char* name, double ms) {
        for (auto& t : times_) {
            if (t.stage == name) {
                t.ms += ms;
                return;
            }
        }
        times_.push_back({name, ms});
    }
    std::vector<StageTiming> times_;
};

Box boundsOf(const landmarks::Shape68& shape) {
    const Eigen::Vector2f lo = shape.rowwise().minCoeff(), hi = shape.rowwise().maxCoeff();
    return {lo.x(), lo.y(), hi.x(), hi.y()};
}

float overlap(const Box& a, const Box& b) {
    const float w = std::min(a.x1, b.x1) - std::max(a.x0, b.x0), h = std::min(a.y1, b.y1) - std::max(a.y0, b.y0);
    if (w <= 0.f || h <= 0.f) return 0.f;
    const float inter = w * h;
    return inter / (a.width() * a.height() + b.width() * b.height() - inter);
}

bool contains(const Box& box, float x, float y) { return x >= box.x0 && x <= box.x1 && y >= box.y0 && y <= box.y1; }

// Failure thresholds: beyond these a followed face is dropped and re-detected.
constexpr float kMaxOutsideShare = 0.25f;   // landmarks outside the frame
constexpr double kMaxPitchDeg = 70.0, kMaxYawDeg = 80.0;
constexpr double kMinDepthCm = 10.0, kMaxDepthCm = 1000.0;
constexpr float kMinEyeCornersPx = 8.f;
constexpr double kMinFaceContrast = 4.0;   // grey-level standard deviation inside the landmarks' box
constexpr int kCalibrationStride = 5;       // frames between calibration samples
constexpr int kVerifyCropWidth = 128;       // px: the verification crop is detected at this width
constexpr float kTranslationScaleMm = 90.f; // ~ an eye-corner distance: the filter's unit of translation speed

}  // namespace

Models Models::loadDefault() {
    Models models;
    models.face = FaceModel::loadDefault();
    const std::string lbf = modelDirectory() + "/landmarks_lbf.ftm";
    std::error_code ec;
    if (std::filesystem::exists(lbf, ec)) {
        models.landmarks = LandmarkModel::load(lbf);
    } else {
        core::log("landmark model " + lbf + " not found: the landmarks stage is not available");
    }
    return models;
}

struct Tracker::Impl {
    Models models;
    TrackerConfig config;
    std::unique_ptr<FaceDetector> detector;
    std::string detector_kind;  // picks the landmark model's box prior; fixed per tracker
    std::shared_ptr<const fit::FitBasis> fit_basis;
    fit::Camera camera;
    cv::Mat gray, crop;  // reused frame to frame
    std::vector<track::FaceTrack> tracks;
    int next_id = 1;
    long frame_index = 0;
    double last_time = std::numeric_limits<double>::quiet_NaN();

    void detectNewFaces(const ImageView& frame);
    bool findLandmarks(track::FaceTrack& face);  // false: lost
    bool fitFace(track::FaceTrack& face);        // false: lost
    bool verify(const track::FaceTrack& face);  // the detector finds it again on a crop of `gray`
    void calibrate(track::FaceTrack& face);
    FaceResult output(track::FaceTrack& face, double dt);
};

Tracker::Tracker(Models models, const TrackerConfig& config) : impl_(std::make_unique<Impl>()) {
    if (!models.face) throw Error("Tracker: no face model given");
    if (config.max_faces < 1) throw Error("TrackerConfig::max_faces must be at least 1");
    if (config.detect_interval < 1) throw Error("TrackerConfig::detect_interval must be at least 1");
    if (config.verify_interval < 0 || config.calibration_frames < 0) {
        throw Error("TrackerConfig::verify_interval and calibration_frames must not be negative");
    }
    if (!(config.max_fit_residual > 0.f)) throw Error("TrackerConfig::max_fit_residual must be positive");
    fit::cameraFor(640, 480, config.camera.horizontal_fov_deg, config.camera.focal_length_px);  // validates
    impl_->models = std::move(models);
    impl_->config = config;
    impl_->detector = createFaceDetector(config.detector);
    impl_->detector_kind = impl_->detector->kind();
    impl_->fit_basis = std::make_shared<const fit::FitBasis>(fit::buildFitBasis(impl_->models.face->data()));
}

Tracker::~Tracker() = default;
Tracker::Tracker(Tracker&&) noexcept = default;
Tracker& Tracker::operator=(Tracker&&) noexcept = default;

void Tracker::Impl::detectNewFaces(const ImageView& frame) {
    for (const auto& d : detector->detect(frame)) {
        if (static_cast<int>(tracks.size()) >= config.max_faces) break;
        const bool known = std::any_of(tracks.begin(), tracks.end(), [&](const track::FaceTrack& t) {
            return overlap(t.box, d.box) > 0.3f || contains(d.box, 0.5f * (t.box.x0 + t.box.x1), 0.5f * (t.box.y0 + t.box.y1));
        });
        if (known) continue;
        track::FaceTrack face;
        face.id = next_id++;
        face.box = d.box;
        const filter::OneEuroSettings f{config.filter.min_cutoff_hz, config.filter.beta, config.filter.derivative_cutoff_hz};
        face.landmark_filter = face.rotation_filter = face.translation_filter = face.expression_filter =
            filter::OneEuroFilter(f);
        face.fitter = std::make_unique<fit::FaceFitter>(fit_basis, fit::FitSettings{});
        tracks.push_back(std::move(face));
    }
}

bool Tracker::Impl::findLandmarks(track::FaceTrack& face) {
    const auto& lbf = models.landmarks->data();
    // Followed faces start from the previous frame's fitted face, projected:
    // starting from the previous landmarks themselves lets their errors
    // accumulate (the residual doubled within a second on the clips); the
    // model's projection is always a plausible face.
    const landmarks::Shape68 start =
        face.fresh ? landmarks::shapeFromBox(lbf, face.box, detector_kind)
                   : landmarks::Shape68(fit::projectLandmarks(*fit_basis, face.fitter->base(), camera, face.params, face.contour)
                                            .cast<float>());
    face.shape = landmarks::alignLandmarks(lbf, gray, start);
    if (!face.shape.allFinite()) return false;
    const Box frame{0.f, 0.f, static_cast<float>(gray.cols - 1), static_cast<float>(gray.rows - 1)};
    int outside = 0;
    for (int i = 0; i < landmarks::kLandmarks; ++i) outside += !contains(frame, face.shape(0, i), face.shape(1, i));
    face.box = boundsOf(face.shape);
    // A face has texture: a covered lens or a blanked frame has none, yet the
    // regression still returns a plausible shape there.
    const cv::Rect region = cv::Rect(cvRound(face.box.x0), cvRound(face.box.y0), cvRound(face.box.width()) + 1,
                                     cvRound(face.box.height()) + 1) &
                            cv::Rect(0, 0, gray.cols, gray.rows);
    if (region.area() <= 0) return false;
    cv::Scalar mean, deviation;
    cv::meanStdDev(gray(region), mean, deviation);
    if (deviation[0] < kMinFaceContrast) return false;
    return outside <= kMaxOutsideShare * landmarks::kLandmarks &&
           fit::eyeCornerDistance(face.shape.cast<double>()) >= kMinEyeCornersPx;
}

bool Tracker::Impl::fitFace(track::FaceTrack& face) {
    const auto report = face.fitter->fit(camera, face.shape.cast<double>(), face.params, face.fitted);
    face.fitted = true;
    face.contour = report.contour;
    face.residual = report.residual;
    const Eigen::Vector3d euler = fit::eulerDegrees(face.params.omega());
    const double depth = face.params.translation().z();
    return report.residual <= config.max_fit_residual && std::abs(euler.x()) <= kMaxPitchDeg &&
           std::abs(euler.y()) <= kMaxYawDeg && depth >= kMinDepthCm && depth <= kMaxDepthCm;
}

void Tracker::Impl::calibrate(track::FaceTrack& face) {
    const Eigen::VectorXd identity = fit::calibrateIdentity(*fit_basis, face.calibration_window, face.fitter->settings());
    face.fitter->setIdentity(identity);
    face.identity_calibrated = true;
    face.calibration_window.clear();
}

bool Tracker::Impl::verify(const track::FaceTrack& face) {
    // A crop twice the landmarks' size, detected small: ~1 ms instead of a full-frame search.
    const float side = 2.f * std::max(face.box.width(), face.box.height());
    const float cx = 0.5f * (face.box.x0 + face.box.x1), cy = 0.5f * (face.box.y0 + face.box.y1);
    const cv::Rect wanted(cvRound(cx - side / 2), cvRound(cy - side / 2), cvRound(side), cvRound(side));
    const cv::Rect region = wanted & cv::Rect(0, 0, gray.cols, gray.rows);
    if (region.area() <= 0) return false;
    const double scale = std::min(1.0, static_cast<double>(kVerifyCropWidth) / region.width);
    cv::resize(gray(region), crop, cv::Size(), scale, scale, cv::INTER_AREA);
    for (const auto& d : detector->detect(core::viewOf(crop))) {
        const float x = region.x + 0.5f * (d.box.x0 + d.box.x1) / static_cast<float>(scale);
        const float y = region.y + 0.5f * (d.box.y0 + d.box.y1) / static_cast<float>(scale);
        if (contains(face.box, x, y)) return true;
    }
    return false;
}

FaceResult Tracker::Impl::output(track::FaceTrack& face, double dt) {
    FaceResult r;
    r.id = face.id;
    r.tracked = !face.fresh;
    r.fit_residual = static_cast<float>(face.residual);
    r.confidence = std::clamp(1.f - static_cast<float>(face.residual) / config.max_fit_residual, 0.f, 1.f);
    r.identity_calibrated = face.identity_calibrated;
    for (const double a : face.fitter->identity()) r.identity.push_back(static_cast<float>(a));

    // Raw estimates.
    r.raw.landmarks = landmarks::toLandmarks68(face.shape);
    const Eigen::Quaterniond rotation(fit::rotationOf(face.params.omega()) * fit::modelToFrontal());
    const Eigen::Vector3d translationMm = face.params.translation() * 10.0;
    r.raw.pose = fit::headPoseOf(rotation, translationMm);
    Eigen::VectorXd native = Eigen::VectorXd::Zero(fit_basis->native_expression_count);
    for (int k = 0; k < fit_basis->expressionCount(); ++k) native[fit_basis->expressions[k]] = face.params.expression[k];
    auto expressionOf = [&](const Eigen::VectorXd& weights) {
        ExpressionResult e;
        e.native.resize(weights.size());
        for (Eigen::Index k = 0; k < weights.size(); ++k) e.native[k] = static_cast<float>(std::clamp(weights[k], 0.0, 1.0));
        e.arkit = models.face->toArkit(e.native);
        return e;
    };
    r.raw.expression = expressionOf(native);

    if (!config.filter.enabled) {
        r.landmarks = r.raw.landmarks;
        r.pose = r.raw.pose;
        r.expression = r.raw.expression;
    } else {
        // Fresh faces restart the filters: no smoothing across a re-detection.
        if (face.fresh) {
            face.landmark_filter.reset();
            face.rotation_filter.reset();
            face.translation_filter.reset();
            face.expression_filter.reset();
        }
        const double eyes = std::max(1.0, fit::eyeCornerDistance(face.shape.cast<double>()));
        const Eigen::VectorXd flat = Eigen::Map<const Eigen::VectorXf>(face.shape.data(), face.shape.size()).cast<double>();
        const Eigen::VectorXd landmarks = face.landmark_filter(flat, dt, eyes);
        landmarks::Shape68 smooth = Eigen::Map<const Eigen::Matrix<double, 2, landmarks::kLandmarks>>(landmarks.data()).cast<float>();
        r.landmarks = landmarks::toLandmarks68(smooth);
        Eigen::Quaterniond q = rotation;
        if (q.coeffs().dot(face.last_rotation.coeffs()) < 0.0) q.coeffs() = -q.coeffs();
        face.last_rotation = q;
        const Eigen::Vector4d qs = face.rotation_filter(q.coeffs(), dt, 1.0);
        const Eigen::Vector3d ts = face.translation_filter(translationMm, dt, kTranslationScaleMm);
        r.pose = fit::headPoseOf(Eigen::Quaterniond(qs), ts);
        r.expression = expressionOf(face.expression_filter(native, dt, 1.0));
    }
    r.box = boundsOf(face.shape);
    return r;
}

FrameResult Tracker::process(const ImageView& frame, double time_s) {
    core::wrap(frame);  // validates the view before any stage touches it
    auto& im = *impl_;
    FrameResult result;
    StageTimes times;
    im.camera = fit::cameraFor(frame.width, frame.height, im.config.camera.horizontal_fov_deg, im.config.camera.focal_length_px);
    result.camera = {static_cast<float>(im.camera.fx), static_cast<float>(im.camera.fy), static_cast<float>(im.camera.cx),
                     static_cast<float>(im.camera.cy)};
    const double dt = std::isfinite(im.last_time) && time_s > im.last_time ? time_s - im.last_time : 1.0 / 30.0;
    im.last_time = time_s;
    const long frameIndex = im.frame_index++;

    if (!im.models.landmarks) {
        // Without landmarks nothing can be followed: detect every frame, report boxes.
        for (const auto& d : times.run("detect", [&] { return im.detector->detect(frame); })) {
            if (static_cast<int>(result.faces.size()) >= im.config.max_faces) break;
            FaceResult face;
            face.confidence = d.score;
            face.box = d.box;
            result.faces.push_back(face);
        }
        result.timings = times.inPipelineOrder();
        return result;
    }

    bool detected = false;
    auto detect = [&] {
        detected = true;
        times.run("detect", [&] { im.detectNewFaces(frame); });
    };
    auto dropLost = [&] {
        im.tracks.erase(std::remove_if(im.tracks.begin(), im.tracks.end(), [](const track::FaceTrack& t) { return t.lost; }),
                        im.tracks.end());
    };
    const int followed = static_cast<int>(im.tracks.size());
    if (followed < im.config.max_faces && (followed == 0 || frameIndex % im.config.detect_interval == 0)) detect();

    bool grayReady = false;
    for (int pass = 0; pass < 2; ++pass) {
        std::vector<track::FaceTrack*> pending;
        for (auto& t : im.tracks) {
            if (t.last_frame != frameIndex) pending.push_back(&t);
        }
        if (!pending.empty()) {
            times.run("landmarks", [&] {
                if (!grayReady) core::toGray(frame, im.gray);
                grayReady = true;
                for (auto* t : pending) {
                    t->last_frame = frameIndex;
                    t->lost = !im.findLandmarks(*t);
                }
            });
            times.run("fit", [&] {
                for (auto* t : pending) {
                    if (!t->lost) t->lost = !im.fitFace(*t);
                }
            });
            dropLost();
        }
        // A followed face was lost and none is left: look again in this very frame.
        if (pass == 0 && im.tracks.empty() && !detected) {
            detect();
        } else {
            break;
        }
    }

    for (auto& t : im.tracks) {
        if (t.identity_calibrated || im.config.calibration_frames == 0 || t.age % kCalibrationStride != 0 ||
            t.residual > 0.5 * im.config.max_fit_residual) {
            continue;
        }
        t.calibration_window.push_back({im.camera, t.shape.cast<double>(), t.params, t.contour});
        if (static_cast<int>(t.calibration_window.size()) >= im.config.calibration_frames) {
            times.run("calibrate", [&] { im.calibrate(t); });
        }
    }
    if (im.config.verify_interval > 0) {
        for (auto& t : im.tracks) {
            if (t.fresh || t.age % im.config.verify_interval != 0) continue;
            times.run("verify", [&] { t.lost = !im.verify(t); });
        }
        dropLost();
    }

    auto report = [&] {
        for (auto& t : im.tracks) {
            result.faces.push_back(im.output(t, dt));
            t.fresh = false;
            ++t.age;
        }
    };
    if (im.config.filter.enabled) {
        times.run("filter", report);
    } else {
        report();
    }
    result.timings = times.inPipelineOrder();
    return result;
}

void Tracker::reset() {
    impl_->tracks.clear();
    impl_->last_time = std::numeric_limits<double>::quiet_NaN();
}

void Tracker::resetIdentity() {
    for (auto& t : impl_->tracks) {
        t.fitter->setIdentity({});
        t.identity_calibrated = false;
        t.calibration_window.clear();
    }
}

std::vector<StageInfo> Tracker::stages() const {
    const auto& detector = *impl_->detector;
    const auto& lbf = impl_->models.landmarks;
    const auto& basis = *impl_->fit_basis;
    const auto& filter = impl_->config.filter;
    char filterDetail[96];
    std::snprintf(filterDetail, sizeof filterDetail, "1-euro (min cutoff %g Hz, beta %g)", filter.min_cutoff_hz, filter.beta);
    return {
        {"detect", true, detector.kind() + " (" + detector.modelPath() + "), when no face is followed"},
        lbf ? StageInfo{"landmarks", true,
                        "LBF, " + std::to_string(lbf->stageCount()) + " stages (" + lbf->sourcePath() + ")"}
            : StageInfo{"landmarks", false, "not available: no landmark model loaded"},
        lbf ? StageInfo{"fit", true,
                        "Ceres: pose, " + std::to_string(basis.expressionCount()) + " expressions, " +
                            std::to_string(basis.identityCount()) + " identity modes"}
            : StageInfo{"fit", false, "not available: needs the landmarks stage"},
        {"cnn", false, "not available: the CNN refinement cascade is not built yet"},
        {"gaze", false, "not available: eye gaze is not built yet"},
        filter.enabled ? StageInfo{"filter", true, filterDetail}
                       : StageInfo{"filter", false, "off (TrackerConfig::filter.enabled)"},
    };
}

const Models& Tracker::models() const { return impl_->models; }

}  // namespace facetrack
