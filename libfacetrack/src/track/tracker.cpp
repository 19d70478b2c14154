#include "facetrack/tracker.hpp"

#include "core/environment.hpp"
#include "core/image.hpp"
#include "facetrack/error.hpp"
#include "facetrack/version.hpp"
#include "landmarks/lbf.hpp"

#include <chrono>
#include <filesystem>

namespace facetrack {

namespace {

/// Runs one stage and appends its wall-clock time to the frame's timings.
template <class Stage>
auto timed(std::vector<StageTiming>& timings, const char* name, Stage&& stage) {
    const auto start = std::chrono::steady_clock::now();
    auto output = stage();
    const std::chrono::duration<double, std::milli> elapsed = std::chrono::steady_clock::now() - start;
    timings.push_back({name, elapsed.count()});
    return output;
}

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
    cv::Mat gray;               // reused frame to frame
};

Tracker::Tracker(Models models, const TrackerConfig& config) : impl_(std::make_unique<Impl>()) {
    if (!models.face) throw Error("Tracker: no face model given");
    if (config.max_faces < 1) throw Error("TrackerConfig::max_faces must be at least 1");
    impl_->models = std::move(models);
    impl_->config = config;
    impl_->detector = createFaceDetector(config.detector);
    impl_->detector_kind = impl_->detector->kind();
}

Tracker::~Tracker() = default;
Tracker::Tracker(Tracker&&) noexcept = default;
Tracker& Tracker::operator=(Tracker&&) noexcept = default;

FrameResult Tracker::process(const ImageView& frame, double /*time_s: for the filter stage*/) {
    core::wrap(frame);  // validates the view before any stage touches it
    FrameResult result;
    auto detections = timed(result.timings, "detect", [&] { return impl_->detector->detect(frame); });
    if (detections.size() > static_cast<std::size_t>(impl_->config.max_faces)) {
        detections.resize(impl_->config.max_faces);
    }
    for (const auto& d : detections) {
        FaceResult face;
        face.tracked = false;
        face.confidence = d.score;
        face.box = d.box;
        result.faces.push_back(face);
    }

    if (const auto& lbf = impl_->models.landmarks; lbf && !result.faces.empty()) {
        timed(result.timings, "landmarks", [&] {
            const cv::Mat gray = core::toGray(frame, impl_->gray);
            for (auto& face : result.faces) {
                const auto init = landmarks::shapeFromBox(lbf->data(), face.box, impl_->detector_kind);
                face.landmarks = landmarks::toLandmarks68(landmarks::alignLandmarks(lbf->data(), gray, init));
            }
            return 0;
        });
    }
    return result;
}

std::vector<StageInfo> Tracker::stages() const {
    const auto& detector = *impl_->detector;
    const auto& lbf = impl_->models.landmarks;
    return {
        {"detect", true, detector.kind() + " (" + detector.modelPath() + ")"},
        lbf ? StageInfo{"landmarks", true,
                        "LBF, " + std::to_string(lbf->stageCount()) + " stages (" + lbf->sourcePath() + ")"}
            : StageInfo{"landmarks", false, "not available: no landmark model loaded"},
        {"fit", false, "not available: 3D pose and expression fitting is not built yet"},
        {"cnn", false, "not available: the CNN refinement cascade is not built yet"},
        {"gaze", false, "not available: eye gaze is not built yet"},
        {"filter", false, "not available: temporal filtering is not built yet"},
    };
}

const Models& Tracker::models() const { return impl_->models; }

}  // namespace facetrack
