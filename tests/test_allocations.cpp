// No heap allocation per tracked frame: a counting global operator new around
// Tracker::process on a real clip. Its own program, so that the counting
// operator new sees nothing but this test.

#include "facetrack/facetrack.hpp"
#include "test_support.hpp"

#include <opencv2/videoio.hpp>

#include <atomic>
#include <cstdlib>
#include <new>

namespace {
std::atomic<long> allocations{0};
}  // namespace

void* operator new(std::size_t size) {
    allocations.fetch_add(1, std::memory_order_relaxed);
    if (void* p = std::malloc(size ? size : 1)) return p;
    throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
    allocations.fetch_add(1, std::memory_order_relaxed);
    return std::malloc(size ? size : 1);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept { return operator new(size, tag); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace facetrack {
namespace {

TEST(Allocations, NonePerTrackedFrameAfterWarmUp) {
    FACETRACK_REQUIRE_SHARED();
    if (!std::filesystem::exists(test::sourceDir() + "/models/landmarks_lbf.ftm")) GTEST_SKIP() << "no landmark model";
    const std::vector<cv::Mat> frames = test::clipFrames(300);
    ASSERT_EQ(frames.size(), 300u);

    Tracker tracker(Models::loadDefault());
    FrameResult result;
    // Warm-up: detection, then identity calibration (30 samples, one every 5 frames).
    constexpr std::size_t kWarmUp = 160;
    long trackedFrames = 0, verifyFrames = 0, allocationsElsewhere = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
        const ImageView view{frames[i].data, frames[i].cols, frames[i].rows, frames[i].step[0], PixelFormat::Bgr8};
        const long before = allocations.load();
        tracker.process(view, i / 30.0, result);
        const long made = allocations.load() - before;
        if (i < kWarmUp) continue;
        ASSERT_EQ(result.faces.size(), 1u) << "frame " << i;
        ASSERT_TRUE(result.faces[0].identity_calibrated) << "frame " << i;
        bool searched = false;
        for (const auto& t : result.timings) searched |= t.stage == "detect" || t.stage == "verify";
        if (searched) {
            // The detector (OpenCV's dnn) allocates on every run: docs/architecture.md lists it.
            ++verifyFrames;
            allocationsElsewhere += made;
            continue;
        }
        ++trackedFrames;
        EXPECT_EQ(made, 0) << "frame " << i << " allocated " << made << " times";
    }
    std::printf("%ld tracked frames without allocation; %ld frames ran the detector (%ld allocations)\n", trackedFrames,
                verifyFrames, allocationsElsewhere);
    EXPECT_GT(trackedFrames, 120);
    EXPECT_GT(allocationsElsewhere, 0);  // the counter does see the library's allocations
    EXPECT_LE(verifyFrames, 6);  // every 30th frame
}

}  // namespace
}  // namespace facetrack
