#pragma once
// Inputs for the benchmarks. Run them on one core: taskset -c 0 (docs/benchmarks.md).

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>

#include <string>

namespace facetrack::bench {

/// Frame `index` of a clip in ../shared/data/clips, resized to width x height
/// (the clips are at most 512 px; webcam benchmarks use 640x480). Empty when
/// ../shared is absent.
cv::Mat clipFrame(const std::string& clip, int index, int width, int height);

/// Marks the benchmark skipped when the frame could not be loaded; true if so.
bool skipWithoutShared(benchmark::State& state, const cv::Mat& frame);

}  // namespace facetrack::bench
