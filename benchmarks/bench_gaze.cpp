// The gaze stage alone, both eyes of one face (patches, the iris CNN or the
// pixel forest, the aperture forest, binocular fit), on a tracked 640x480
// frame; and the whole tracking frame with and without it, in the same run
// (bench_tracking.cpp's loop). FACETRACK_EYE_MODEL names another eye model
// than the shipped one (a candidate, before it is shipped).

#include "bench_support.hpp"

#include "core/environment.hpp"
#include "core/image.hpp"
#include "facetrack/facetrack.hpp"
#include "gaze/eye_model_data.hpp"
#include "gaze/gaze_stage.hpp"
#include "model/internals.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <cstdlib>
#include <vector>

namespace facetrack::bench {
namespace {

/// The eye model to measure: FACETRACK_EYE_MODEL, else the shipped one.
Models benchModels() {
    Models models = Models::loadDefault();
    if (const char* given = std::getenv("FACETRACK_EYE_MODEL")) models.eyes = EyeModel::load(given);
    return models;
}

/// The gaze stage of `eyes`, timed on tracked 640x480 frames of d14 (`indices`) in turn.
void timeGazeStage(benchmark::State& state, const Models& models, std::shared_ptr<const EyeModel> eyes, const std::vector<int>& indices) {
    std::vector<TrackedFrame> frames;
    for (const int index : indices) {
        auto tracked = trackedFrame(state, models, "liveportrait_d14_gaze_shifts.mp4", index);
        if (!tracked) return;
        frames.push_back(std::move(*tracked));
    }
    auto stage = gaze::makeGazeStage(std::move(eyes), models.face);
    auto faceState = stage->newFaceState();
    std::vector<pipeline::FaceTrack> faces(frames.size());
    std::vector<pipeline::FrameInput> inputs;
    for (std::size_t i = 0; i < frames.size(); ++i) {
        faces[i].result = frames[i].result.faces[0];
        inputs.push_back(frames[i].input());
    }
    std::size_t i = 0;
    for (auto _ : state) {
        stage->run(inputs[i], faces[i], faceState.get());
        benchmark::DoNotOptimize(faces[i].result.gaze);
        i = (i + 1) % frames.size();
    }
}

/// Both eyes of frame 40, repeated. Arg 0: the pixel forest (the model's iris CNN left out); 1: the
/// model as it is (its iris CNN when it has one).
void BM_Gaze_BothEyes(benchmark::State& state) {
    const Models models = benchModels();
    if (!models.eyes) {
        failBenchmark(state, "no eye model (models/eye_model.ftm is shipped)");
        return;
    }
    std::shared_ptr<const EyeModel> eyes = models.eyes;
    const bool cnn = state.range(0) == 1 && !model::dataOf(*eyes).iris_net.empty();
    if (state.range(0) == 0 && !model::dataOf(*eyes).iris_net.empty()) {
        gaze::EyeModelData forest = model::dataOf(*eyes);
        forest.iris_net.clear();
        eyes = model::Internals::make(std::move(forest), eyes->sourcePath());
    }
    state.SetLabel(cnn ? "iris CNN" : "pixel forest");
    timeGazeStage(state, models, eyes, {40});
}
BENCHMARK(BM_Gaze_BothEyes)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond)->MinTime(minTime(2.0));

/// The same stage, the model as it is, on 16 frames in turn (every fifth from frame 40). Why: on one
/// frame repeated the stage reads about half what it costs in the tracker, most likely because the
/// branch predictor learns every forest walk's path.
void BM_Gaze_BothEyesFramesInTurn(benchmark::State& state) {
    const Models models = benchModels();
    if (!models.eyes) {
        failBenchmark(state, "no eye model (models/eye_model.ftm is shipped)");
        return;
    }
    state.SetLabel(model::dataOf(*models.eyes).iris_net.empty() ? "pixel forest" : "iris CNN");
    std::vector<int> indices;
    for (int index = 40; index < 40 + 16 * 5; index += 5) indices.push_back(index);
    timeGazeStage(state, models, models.eyes, indices);
}
BENCHMARK(BM_Gaze_BothEyesFramesInTurn)->Unit(benchmark::kMicrosecond)->MinTime(minTime(2.0));

/// The tracking-mode frame of d14 at 640x480, gaze on (the shipped models) or off (no eye model).
void BM_TrackingFrame640x480_d14(benchmark::State& state) {
    std::vector<cv::Mat> frames;
    cv::VideoCapture video(core::sharedDirectory() + "/data/clips/liveportrait_d14_gaze_shifts.mp4");
    for (cv::Mat frame, resized; frames.size() < 120 && video.read(frame);) {
        cv::resize(frame, resized, cv::Size(640, 480));
        frames.push_back(resized.clone());
    }
    if (skipWithoutShared(state, frames.empty() ? cv::Mat() : frames[0])) return;
    Models models = benchModels();
    if (state.range(0) == 0) models.eyes = nullptr;
    const std::string cascade = benchCascadePath();  // the shipped CNN file or FACETRACK_CNN_CASCADE; a missing path: none
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
    state.SetLabel(std::string(state.range(0) ? "gaze on" : "gaze off") + (models.cnn ? ", CNN file on" : ""));
}
BENCHMARK(BM_TrackingFrame640x480_d14)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->MinTime(minTime(3.0));

}  // namespace
}  // namespace facetrack::bench
