// No heap allocation per tracked frame but OpenCV's warpAffine in the refine
// stage: a counting global operator new around Tracker::process on a real clip.
// Its own program, so that the counting operator new sees nothing but this test.

#include "cnn/cnn_model_data.hpp"
#include "cnn/landmark_refiner.hpp"
#include "cnn/patch_net.hpp"
#include "facetrack/facetrack.hpp"
#include "test_support.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <atomic>
#include <cstdlib>
#include <filesystem>
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

/// Allocations of each tracked frame after warm-up (frames that ran the detector left out), over
/// 300 frames of a clip; `verifyFrames`: how many ran the detector, `allocationsElsewhere`: what they allocated.
std::vector<long> trackedFrameAllocations(const Models& models, long& verifyFrames, long& allocationsElsewhere) {
    const std::vector<cv::Mat> frames = test::clipFrames(300);
    EXPECT_EQ(frames.size(), 300u);
    Tracker tracker(models);
    FrameResult result;
    // Warm-up: detection, then identity calibration (30 samples, one every 5 frames).
    constexpr std::size_t kWarmUp = 160;
    std::vector<long> tracked;
    verifyFrames = allocationsElsewhere = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
        const ImageView view{frames[i].data, frames[i].cols, frames[i].rows, frames[i].step[0], PixelFormat::Bgr8};
        const long before = allocations.load();
        tracker.process(view, i / 30.0, result);
        const long made = allocations.load() - before;
        if (i < kWarmUp) continue;
        EXPECT_EQ(result.faces.size(), 1u) << "frame " << i;
        if (result.faces.empty()) continue;
        EXPECT_TRUE(result.faces[0].identity_calibrated) << "frame " << i;
        bool searched = false;
        for (const auto& t : result.timings) searched |= t.stage == "detect" || t.stage == "verify";
        if (searched) {
            // The detector (OpenCV's dnn) allocates on every run: docs/architecture.md lists it.
            ++verifyFrames;
            allocationsElsewhere += made;
            continue;
        }
        tracked.push_back(made);
    }
    return tracked;
}

TEST(Allocations, NonePerTrackedFrameAfterWarmUp) {
    FACETRACK_REQUIRE_SHARED();
    if (!std::filesystem::exists(test::sourceDir() + "/models/landmarks_lbf.ftm")) GTEST_SKIP() << "no landmark model";
    Models models = Models::loadDefault();
    models.cnn = nullptr;  // the CNN stages run OpenCV's dnn, which allocates: the test below
    long verifyFrames = 0, allocationsElsewhere = 0;
    const std::vector<long> tracked = trackedFrameAllocations(models, verifyFrames, allocationsElsewhere);
    for (std::size_t i = 0; i < tracked.size(); ++i) EXPECT_EQ(tracked[i], 0) << "tracked frame " << i << " allocated";
    std::printf("%zu tracked frames without allocation; %ld frames ran the detector (%ld allocations)\n", tracked.size(),
                verifyFrames, allocationsElsewhere);
    EXPECT_GT(tracked.size(), 120u);
    EXPECT_GT(allocationsElsewhere, 0);  // the counter does see the library's allocations
    EXPECT_LE(verifyFrames, 6);  // every 30th frame
}

// With the shipped CNN file, a tracked frame allocates exactly what one run of the refiner does
// (cv::warpAffine cutting its patch; the nets run on the own kernels, which allocate nothing), or
// two where the stage runs its second round, and the brow and eye refiner's one run on both sides
// when the file has it, and nothing else (docs/architecture.md).
// On one OpenCV thread: with a pool, what a run allocates depends on which worker joined it and
// whether that worker had run the net before (CI saw 130 against 127 in one process).
TEST(Allocations, WithTheRefinerOnlyItsPatchWarpsAllocate) {
    FACETRACK_REQUIRE_SHARED();
    if (!std::filesystem::exists(CnnModel::defaultPath())) GTEST_SKIP() << "no CNN file in models/";
    const int threads = cv::getNumThreads();
    cv::setNumThreads(1);
    const Models models = Models::loadDefault();
    ASSERT_TRUE(models.cnn && models.cnn->hasRefiner() && !models.cnn->hasCascade());
    // One run of the refiner as the stage makes it (the aligned patch, the net, the blend) on a
    // frame of the clip, with the mean shape as LBF's points.
    const cnn::CnnModelData& d = models.cnn->data();
    const cnn::RefinerLayout layout = cnn::makeRefinerLayout(d);
    cnn::PatchNet net(d.refiner_net, layout.size, 136, "refiner");
    cv::Mat gray, patch;
    cv::cvtColor(test::clipFrames(1)[0], gray, cv::COLOR_BGR2GRAY);
    const landmarks::Shape68 points = (2.f * layout.mean).colwise() + Eigen::Vector2f(60.f, 40.f);
    long perRun = 0;
    for (int run = 0; run < 2; ++run) {  // the first warms
        const long before = allocations.load();
        const core::Similarity toFrame = cnn::patchToFrame(layout, points);
        cnn::warpAligned(layout, gray, toFrame, patch);
        const long beforeNet = allocations.load();
        const Eigen::VectorXd& offsets = net.predict(patch);
        if (run > 0) {
            EXPECT_EQ(allocations.load() - beforeNet, 0) << "the refiner's net allocated";
        }
        const landmarks::Shape68 refined = cnn::refinedLandmarks(layout, toFrame, offsets, points);
        EXPECT_TRUE(refined.allFinite());
        perRun = allocations.load() - before;
    }
    // And, with the brow and eye refiner, its run on both sides at once, after the refiner's.
    long sides = 0;
    if (!d.side_net.empty()) {
        const cnn::SideLayout sideLayout = cnn::makeSideLayout(d);
        cnn::PatchNet sideNet(d.side_net, sideLayout.size, 22, "brow and eye refiner", 2);
        std::array<cv::Mat, 2> sidePatches;
        for (int run = 0; run < 2; ++run) {
            const long before = allocations.load();
            landmarks::Shape68 refined = points;
            cnn::refineSides(sideLayout, sideNet, gray, sidePatches, refined);
            EXPECT_TRUE(refined.allFinite());
            sides = allocations.load() - before;
        }
    }
    long verifyFrames = 0, allocationsElsewhere = 0;
    const std::vector<long> tracked = trackedFrameAllocations(models, verifyFrames, allocationsElsewhere);
    int twice = 0;
    for (std::size_t i = 0; i < tracked.size(); ++i) {
        EXPECT_TRUE(tracked[i] == perRun + sides || tracked[i] == 2 * perRun + sides) << "tracked frame " << i << ": " << tracked[i];
        twice += tracked[i] == 2 * perRun + sides;
    }
    std::printf("%zu tracked frames, each %ld allocations: one run of the refiner (cv::warpAffine), %ld of the brow and "
                "eye refiner's (both sides in one run); %d with a second run of the refiner\n",
                tracked.size(), perRun + sides, sides, twice);
    EXPECT_GT(tracked.size(), 120u);
    cv::setNumThreads(threads);
}

}  // namespace
}  // namespace facetrack
