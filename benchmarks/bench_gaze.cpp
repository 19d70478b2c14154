// The gaze stage alone, both eyes of one face (patches, pixel and aperture
// forests, binocular fit), on a tracked 640x480 frame; and the whole tracking
// frame with and without it, in the same run (bench_tracking.cpp's loop).

#include "bench_support.hpp"

#include "core/environment.hpp"
#include "core/image.hpp"
#include "gaze/gaze_stage.hpp"
#include "facetrack/facetrack.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

namespace facetrack::bench {
namespace {

void BM_Gaze_BothEyes(benchmark::State& state) {
    Models models = Models::loadDefault();
    if (!models.eyes) {
        state.SkipWithError("no eye model");
        return;
    }
    const auto tracked = trackedFrame(state, models, "liveportrait_d14_gaze_shifts.mp4", 40);
    if (!tracked) return;
    auto stage = gaze::makeGazeStage(models.eyes, models.face, true);
    auto faceState = stage->newFaceState();
    pipeline::FaceTrack face;
    face.result = tracked->result.faces[0];
    const pipeline::FrameInput input = tracked->input();
    for (auto _ : state) {
        stage->run(input, face, faceState.get());
        benchmark::DoNotOptimize(face.result.gaze);
    }
}
BENCHMARK(BM_Gaze_BothEyes)->Unit(benchmark::kMicrosecond)->MinTime(2.0);

/// The tracking-mode frame of d14 at 640x480, gaze on (the shipped models) or off (no eye model).
void BM_TrackingFrame640x480_d14(benchmark::State& state) {
    std::vector<cv::Mat> frames;
    cv::VideoCapture video(core::sharedDirectory() + "/data/clips/liveportrait_d14_gaze_shifts.mp4");
    for (cv::Mat frame, resized; frames.size() < 120 && video.read(frame);) {
        cv::resize(frame, resized, cv::Size(640, 480));
        frames.push_back(resized.clone());
    }
    if (skipWithoutShared(state, frames.empty() ? cv::Mat() : frames[0])) return;
    Models models = Models::loadDefault();
    if (state.range(0) == 0) models.eyes = nullptr;
    const std::string cascade = benchCascadePath();  // with FACETRACK_CNN_CASCADE: the frame with the cnn stage
    models.cnn = cascade.empty() ? nullptr : CnnModel::load(cascade);
    Tracker tracker(models);
    FrameResult result;
    std::size_t t = 0;
    for (; t < frames.size(); ++t) tracker.process(core::viewOf(frames[t]), t / 30.0, result);
    for (auto _ : state) {
        const std::size_t i = t % (2 * frames.size());
        const std::size_t index = i < frames.size() ? i : 2 * frames.size() - 1 - i;
        tracker.process(core::viewOf(frames[index]), t / 30.0, result);
        ++t;
    }
    state.SetLabel(std::string(state.range(0) ? "gaze on" : "gaze off") + (models.cnn ? ", cnn on" : ""));
}
BENCHMARK(BM_TrackingFrame640x480_d14)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->MinTime(3.0);

}  // namespace
}  // namespace facetrack::bench
