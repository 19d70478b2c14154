#include "bench_support.hpp"

#include "core/environment.hpp"
#include "facetrack/version.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

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

}  // namespace facetrack::bench

int main(int argc, char** argv) {
    facetrack::setLogHandler({});
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
