// No heap allocation per tracked frame, with or without the shipped CNN file: a
// counting global operator new around Tracker::process on a real clip. Its own
// program, so that the counting operator new sees nothing but this test.

#include "facetrack/facetrack.hpp"
#include "model/internals.hpp"
#include "nn/cnn_model_data.hpp"
#include "nn/patch_net.hpp"
#include "refine/landmark_refiner.hpp"
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

// These replacements pair malloc with free by design; GCC, seeing a new-expression inlined next
// to them, warns that free() meets memory from operator new.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif

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
/// `calibrated`: the face's identity is expected calibrated after the warm-up.
std::vector<long> trackedFrameAllocations(const Models& models, long& verifyFrames, long& allocationsElsewhere, bool calibrated = true) {
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
        if (calibrated) {
            EXPECT_TRUE(result.faces[0].identity_calibrated) << "frame " << i;
        }
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
    std::printf("%zu tracked frames without allocation; %ld frames ran the detector (%ld allocations)\n", tracked.size(), verifyFrames,
                allocationsElsewhere);
    EXPECT_GT(tracked.size(), 120u);
    EXPECT_GT(allocationsElsewhere, 0);  // the counter does see the library's allocations
    EXPECT_LE(verifyFrames, 6);          // every 30th frame
}

// With the shipped nets too: the refiners cut their patches by hand (core::warpAffineGray), the
// CNN file's expression stage warps piecewise-affinely into buffers it keeps, and all run their nets on
// the own kernels (nn::ConvChain), so a tracked frame allocates nothing. One run of each
// refiner is checked alone first, so that a failure says which one allocates.
TEST(Allocations, NonePerTrackedFrameWithTheShippedNets) {
    FACETRACK_REQUIRE_SHARED();
    if (!std::filesystem::exists(CnnModel::defaultPath()) || !std::filesystem::exists(RefinerModel::defaultPath()))
        GTEST_SKIP() << "no CNN file or landmark refiner in models/";
    const Models models = Models::loadDefault();
    ASSERT_TRUE(models.cnn && models.refiner);
    // One run of the refiner as the stage makes it (the aligned patch, the net, the blend) on a
    // frame of the clip, with the mean shape as LBF's points.
    const nn::RefinerModelData& d = model::dataOf(*models.refiner);
    const refine::RefinerLayout layout = refine::makeRefinerLayout(d);
    nn::PatchNet net(d.net, layout.size, 136, "refiner");
    cv::Mat gray, patch;
    cv::cvtColor(test::clipFrames(1)[0], gray, cv::COLOR_BGR2GRAY);
    const core::Shape68 points = (2.f * layout.mean).colwise() + Eigen::Vector2f(60.f, 40.f);
    for (int run = 0; run < 2; ++run) {  // the first warms
        const long before = allocations.load();
        const core::Similarity toFrame = refine::patchToFrame(layout, points);
        refine::warpAligned(layout, gray, toFrame, patch);
        const long afterWarp = allocations.load();
        const core::Shape68 refined = refine::refinedLandmarks(layout, toFrame, net.predict(patch), points);
        EXPECT_TRUE(refined.allFinite());
        if (run > 0) {
            EXPECT_EQ(afterWarp - before, 0) << "the refiner's patch cut allocated";
            EXPECT_EQ(allocations.load() - afterWarp, 0) << "the refiner's net allocated";
        }
    }
    // And the brow and eye refiner's run on both sides at once.
    if (!d.side_net.empty()) {
        const refine::SideLayout sideLayout = refine::makeSideLayout(d);
        nn::PatchNet sideNet(d.side_net, sideLayout.size, 22, "brow and eye refiner", 2);
        std::array<cv::Mat, 2> sidePatches;
        for (int run = 0; run < 2; ++run) {
            const long before = allocations.load();
            core::Shape68 refined = points;
            refine::refineSides(sideLayout, sideNet, gray, sidePatches, refined);
            EXPECT_TRUE(refined.allFinite());
            if (run > 0) {
                EXPECT_EQ(allocations.load() - before, 0) << "the brow and eye refiner allocated";
            }
        }
    }
    long verifyFrames = 0, allocationsElsewhere = 0;
    const std::vector<long> tracked = trackedFrameAllocations(models, verifyFrames, allocationsElsewhere);
    for (std::size_t i = 0; i < tracked.size(); ++i) EXPECT_EQ(tracked[i], 0) << "tracked frame " << i << " allocated";
    std::printf("%zu tracked frames with the shipped nets, none allocating\n", tracked.size());
    EXPECT_GT(tracked.size(), 120u);
}

// The cnn stage as the thesis's cascade (the shipped one reads only expressions) run by a cascade
// file made of the test fixtures: two rounds of the parity net and the landmark net, after the
// shipped refiners. Its piecewise-affine warp, its nets on the own kernels and its update must
// allocate nothing either.
// The fixtures' updates are not trained: they move the face so that its identity does not finish
// calibrating (not asked here). The frame after each detector check once allocated the tracker's
// appearance buffer again (tracker_core.cpp).
TEST(Allocations, NonePerTrackedFrameWithACascade) {
    FACETRACK_REQUIRE_SHARED();
    if (!std::filesystem::exists(CnnModel::defaultPath())) GTEST_SKIP() << "no CNN file in models/";
    Models models = Models::loadDefault();
    nn::CnnModelData cascade = model::dataOf(*models.cnn);
    cascade.expressions = {"jawOpen"};
    cascade.expressions_only = cascade.corrects_fit = cascade.mirror_averaged = false;  // the shipped expression stage's
    cascade.neutral.clear();
    cascade.full.clear();
    cascade.reported.clear();
    cascade.geometry_net.clear();
    cascade.geometry_reported.clear();
    cascade.geometry_neutral.clear();
    cascade.geometry_full.clear();
    cascade.lip_net.clear();
    cascade.stages.assign(1, {2, test::fixtureBytes("cnn_parity.onnx")});
    cascade.landmark_net = test::fixtureBytes("cnn_landmarks_fixture.onnx");
    const std::string path = test::tempPath("cascade_allocations.ftm");
    nn::writeCnnModel(path, cascade);
    models.cnn = CnnModel::load(path);
    ASSERT_TRUE(models.cnn->hasLandmarkNet() && models.refiner);
    long verifyFrames = 0, allocationsElsewhere = 0;
    const std::vector<long> tracked = trackedFrameAllocations(models, verifyFrames, allocationsElsewhere, false);
    for (std::size_t i = 0; i < tracked.size(); ++i) EXPECT_EQ(tracked[i], 0) << "tracked frame " << i << " allocated";
    std::printf("%zu tracked frames with a cascade of two rounds and a landmark net, none allocating\n", tracked.size());
    EXPECT_GT(tracked.size(), 120u);
}

}  // namespace
}  // namespace facetrack
