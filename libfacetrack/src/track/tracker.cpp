#include "facetrack/tracker.hpp"

#include "core/image.hpp"
#include "facetrack/error.hpp"

#include <chrono>

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

struct Tracker::Impl {
    std::shared_ptr<const FaceModel> model;
    TrackerConfig config;
    std::unique_ptr<FaceDetector> detector;
};

Tracker::Tracker(std::shared_ptr<const FaceModel> model, const TrackerConfig& config)
    : impl_(std::make_unique<Impl>()) {
    if (!model) throw Error("Tracker: no face model given");
    if (config.max_faces < 1) throw Error("TrackerConfig::max_faces must be at least 1");
    impl_->model = std::move(model);
    impl_->config = config;
    impl_->detector = createFaceDetector(config.detector);
}

Tracker::~Tracker() = default;
Tracker::Tracker(Tracker&&) noexcept = default;
Tracker& Tracker::operator=(Tracker&&) noexcept = default;

FrameResult Tracker::process(const ImageView& frame, double /*time_s: for the filter stage*/) {
    core::wrap(frame);  // validates the view before any stage touches it
    FrameResult result;
    const auto detections = timed(result.timings, "detect", [&] { return impl_->detector->detect(frame); });
    for (const auto& d : detections) {
        if (result.faces.size() >= static_cast<std::size_t>(impl_->config.max_faces)) break;
        FaceResult face;
        face.tracked = false;
        face.confidence = d.score;
        face.box = d.box;
        result.faces.push_back(face);
    }
    return result;
}

std::vector<StageInfo> Tracker::stages() const {
    const auto& detector = *impl_->detector;
    return {
        {"detect", true, detector.kind() + " (" + detector.modelPath() + ")"},
        {"landmarks", false, "not available: LBF landmarks are not built yet"},
        {"fit", false, "not available: 3D pose and expression fitting is not built yet"},
        {"cnn", false, "not available: the CNN refinement cascade is not built yet"},
        {"gaze", false, "not available: eye gaze is not built yet"},
        {"filter", false, "not available: temporal filtering is not built yet"},
    };
}

const FaceModel& Tracker::model() const { return *impl_->model; }

}  // namespace facetrack
