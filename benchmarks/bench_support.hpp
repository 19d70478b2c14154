#pragma once
// Inputs for the benchmarks. Run them on one core: taskset -c 0 (docs/benchmarks.md).

#include "pipeline/stage.hpp"

#include "facetrack/cnn_model.hpp"
#include "facetrack/tracker.hpp"

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>

#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

namespace facetrack::bench {

/// Frame `index` of a clip in ../shared/data/clips, resized to width x height
/// (the clips are at most 512 px; webcam benchmarks use 640x480). Empty when
/// ../shared is absent.
cv::Mat clipFrame(const std::string& clip, int index, int width, int height);

/// Marks the benchmark skipped when the frame could not be loaded; true if so.
bool skipWithoutShared(benchmark::State& state, const cv::Mat& frame);

/// Stops a benchmark whose setup is broken (a shipped model missing, no face where one is): it is
/// reported like a skip, but the run then exits with status 1, so the smoke test fails. A missing
/// optional input (../shared, a peer's model, a CNN file that is not shipped) is a skip instead.
void failBenchmark(benchmark::State& state, const std::string& why);

/// A frame after a few frames of tracking with `models`: a stage's input, to
/// run one stage alone on a followed face.
struct TrackedFrame {
    cv::Mat frame, gray;
    FrameResult result;  ///< faces[0] is the followed face
    core::Camera camera;
    pipeline::FrameInput input() const;
};

/// Empty (and the benchmark marked skipped) without ../shared or a face.
/// The CNN cascade to measure: FACETRACK_CNN_CASCADE when set, else the shipped one; its path,
/// or "" when neither exists.
inline std::string benchCascadePath() {
    const char* given = std::getenv("FACETRACK_CNN_CASCADE");
    const std::string path = given ? given : CnnModel::defaultPath();
    return std::filesystem::exists(path) ? path : "";
}

/// A benchmark's minimum time: `seconds`, or next to nothing (one pass) when FACETRACK_BENCH_SMOKE is
/// set: the smoke test runs every benchmark once, so one that breaks fails CI, and times none.
inline double minTime(double seconds) { return std::getenv("FACETRACK_BENCH_SMOKE") ? 1e-9 : seconds; }

std::optional<TrackedFrame> trackedFrame(benchmark::State& state, const Models& models, const std::string& clip, int index);

}  // namespace facetrack::bench
