#include "bench_support.hpp"

#include "core/environment.hpp"
#include "core/image.hpp"
#include "facetrack/version.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <cstdio>

namespace facetrack::bench {

cv::Mat clipFrame(const std::string& clip, int index, int width, int height) {
    const std::string shared = core::sharedDirectory();
    if (shared.empty()) return {};
    cv::VideoCapture video(shared + "/data/clips/" + clip);
    cv::Mat frame;
    for (int i = 0; i <= index; ++i) {
        if (!video.read(frame)) return {};
    }
    cv::Mat resized;
    cv::resize(frame, resized, cv::Size(width, height), 0, 0, cv::INTER_LINEAR);
    return resized;
}

bool skipWithoutShared(benchmark::State& state, const cv::Mat& frame) {
    if (!frame.empty()) return false;
    state.SkipWithError("../shared/data/clips not found (set FACETRACK_SHARED_DIR)");
    return true;
}

namespace {
int brokenBenchmarks = 0;
}  // namespace

void failBenchmark(benchmark::State& state, const std::string& why) {
    ++brokenBenchmarks;
    state.SkipWithError(("broken: " + why).c_str());
}

pipeline::FrameInput TrackedFrame::input() const { return {core::viewOf(frame), gray, camera, 1.0 / 30.0}; }

std::optional<TrackedFrame> trackedFrame(benchmark::State& state, const Models& models, const std::string& clip, int index) {
    TrackedFrame t;
    t.frame = clipFrame(clip, index, 640, 480);
    if (skipWithoutShared(state, t.frame)) return std::nullopt;
    Tracker tracker(models);
    for (int i = 0; i < 5; ++i) tracker.process(core::viewOf(t.frame), i / 30.0, t.result);
    if (t.result.faces.empty()) {
        failBenchmark(state, "no face in frame " + std::to_string(index) + " of " + clip);
        return std::nullopt;
    }
    cv::cvtColor(t.frame, t.gray, cv::COLOR_BGR2GRAY);
    const CameraIntrinsics& c = t.result.camera;
    t.camera.fx = c.fx, t.camera.fy = c.fy, t.camera.cx = c.cx, t.camera.cy = c.cy;
    return t;
}

}  // namespace facetrack::bench

int main(int argc, char** argv) {
    facetrack::setLogHandler({});
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    if (facetrack::bench::brokenBenchmarks > 0) {
        std::fprintf(stderr, "facetrack_bench: %d benchmark(s) broken (reported as \"broken: ...\" above)\n",
                     facetrack::bench::brokenBenchmarks);
        return 1;
    }
    return 0;
}
