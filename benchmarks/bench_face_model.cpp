// Loading the shipped face model: what an app pays once at start-up.

#include "bench_support.hpp"

#include "facetrack/face_model.hpp"
#include "facetrack/version.hpp"

namespace facetrack::bench {
namespace {

void BM_FaceModelLoad(benchmark::State& state) {
    const std::string path = modelDirectory() + "/face_model.ftm";
    for (auto _ : state) benchmark::DoNotOptimize(FaceModel::load(path));
}
BENCHMARK(BM_FaceModelLoad)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace facetrack::bench
