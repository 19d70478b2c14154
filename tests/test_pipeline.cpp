// The Tracker's stage machinery with fake stages and a fake detector, in the
// style of MediaPipe's CalculatorRunner: no models, no images with faces.

#include "calibration/calibration_stage.hpp"
#include "pipeline/stage.hpp"
#include "track/tracker_core.hpp"

#include "facetrack/error.hpp"
#include "facetrack/tracker.hpp"
#include "test_support.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace facetrack {
namespace {

/// Finds the bright square of the test frame (the bounding box of grey levels
/// above 150, in whatever image or crop it is given; none while `present` is
/// false), counting calls. On StageRunner's frame: (20, 10, 60, 50).
class FakeDetector final : public FaceDetector {
public:
    explicit FakeDetector(int* calls, const bool* present = nullptr) : calls_(calls), present_(present) {}
    std::vector<Detection> detect(const ImageView& image) override {
        ++*calls_;
        if (present_ && !*present_) return {};
        int x0 = image.width, y0 = image.height, x1 = -1, y1 = -1;
        for (int y = 0; y < image.height; ++y) {
            for (int x = 0; x < image.width; ++x) {
                if (image.data[static_cast<std::size_t>(y) * image.stride + x] <= 150) continue;
                x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x + 1), y1 = std::max(y1, y + 1);
            }
        }
        if (x1 < 0) return {};
        return {{{static_cast<float>(x0), static_cast<float>(y0), static_cast<float>(x1), static_cast<float>(y1)}, 0.9f}};
    }
    std::string kind() const override { return "fake"; }
    std::string modelPath() const override { return "none"; }

private:
    int* calls_;
    const bool* present_;
};

/// 80 x 60 grey 100 with a bright square, the fake detector's face, at (20, 10)-(60, 50).
std::vector<std::uint8_t> frameWithAFace() {
    std::vector<std::uint8_t> p(80 * 60, 100);
    for (int y = 10; y < 50; ++y) std::fill(p.begin() + y * 80 + 20, p.begin() + y * 80 + 60, std::uint8_t{200});
    return p;
}

struct Counter final : pipeline::StageState {
    int runs = 0;
    int resets = 0;
};

/// Appends its name to a log when it runs, moves the face one pixel right,
/// writes fit_residual = its index; loses the face on the frames listed in
/// `fail_on`, doubts or unsettles it on `doubt_on`, `unsettle_on`.
class FakeStage final : public pipeline::Stage {
public:
    FakeStage(std::string name, bool available, std::vector<std::string>* log, float index)
        : name_(std::move(name)), available_(available), log_(log), index_(index) {}
    std::vector<int> fail_on;      // frame numbers (0-based) on which run() reports a lost face
    std::vector<int> doubt_on;     // frame numbers on which a followed face is moved by doubt_jump and doubted
    std::vector<int> unsettle_on;  // frame numbers on which a followed face is marked unsettled
    float doubt_jump = 0.f;
    int frame = -1;               // set by the test before each process()
    Counter seen;                 // the face state's counters as of the last run
    double dt = 0.0;              // the last run's FrameInput::dt
    pipeline::Contract declared;  // what contract() says
    pipeline::Upstream told;      // what connect() was told
    bool connected = false;

    StageInfo info() const override { return {name_, available_, available_ ? "fake" : "not available: fake"}; }
    pipeline::Contract contract() const override { return declared; }
    void connect(const pipeline::Upstream& upstream) override {
        told = upstream;
        connected = true;
    }
    std::unique_ptr<pipeline::StageState> newFaceState() const override { return std::make_unique<Counter>(); }
    pipeline::Outcome run(const pipeline::FrameInput& input, pipeline::FaceTrack& face, pipeline::StageState* state) override {
        EXPECT_TRUE(connected);  // the Tracker connects every stage it runs
        EXPECT_GT(input.dt, 0.0);
        dt = input.dt;
        EXPECT_EQ(input.gray.cols, input.colour.width);  // grey is ready for every stage
        log_->push_back(name_);
        ++static_cast<Counter&>(*state).runs;
        seen = static_cast<Counter&>(*state);
        face.result.fit_residual = index_;
        if (!available_) face.result.gaze.emplace();  // must never happen: the Tracker does not run it
        Box moved = face.box;
        const bool doubt = !face.fresh && std::find(doubt_on.begin(), doubt_on.end(), frame) != doubt_on.end();
        const float step = 1.f + (doubt ? doubt_jump : 0.f);
        moved.x0 += step;
        moved.x1 += step;
        face.locate(moved);
        if (std::find(fail_on.begin(), fail_on.end(), frame) != fail_on.end()) return pipeline::Outcome::Lost;
        if (doubt) return pipeline::Outcome::Doubtful;
        if (!face.fresh && std::find(unsettle_on.begin(), unsettle_on.end(), frame) != unsettle_on.end())
            return pipeline::Outcome::Unsettled;
        return pipeline::Outcome::Ok;
    }
    void resetIdentity(pipeline::StageState* state) const override { ++static_cast<Counter&>(*state).resets; }

private:
    std::string name_;
    bool available_;
    std::vector<std::string>* log_;
    float index_;
};

class StageRunner : public ::testing::Test {
protected:
    /// A TrackerCore with stages named `names` (a '-' prefix: not available),
    /// each declaring `contracts[i]` when given.
    void build(const std::vector<std::string>& names, int verifyInterval = 0, const std::vector<pipeline::Contract>& contracts = {}) {
        pipeline::StageList stages;
        for (std::size_t i = 0; i < names.size(); ++i) {
            const bool available = names[i][0] != '-';
            auto stage = std::make_unique<FakeStage>(available ? names[i] : names[i].substr(1), available, &log, static_cast<float>(i));
            if (i < contracts.size()) stage->declared = contracts[i];
            fakes.push_back(stage.get());
            stages.push_back(std::move(stage));
        }
        track::LifecycleSettings settings;
        settings.verify_interval = verifyInterval;
        core = std::make_unique<track::TrackerCore>(std::make_unique<FakeDetector>(&detections, &present), std::move(stages), settings);
    }
    FrameResult& step(const std::vector<Box>* boxes = nullptr) {
        for (auto* f : fakes) f->frame = frame;
        log.clear();
        core->process({pixels.data(), 80, 60, 80, PixelFormat::Gray8}, frame / 30.0, boxes, out);
        ++frame;
        return out;
    }
    static std::vector<std::string> names(const FrameResult& r) {
        std::vector<std::string> n;
        for (const auto& t : r.timings) n.push_back(t.stage);
        return n;
    }

    std::vector<std::uint8_t> pixels = frameWithAFace();
    std::vector<std::string> log;
    std::vector<FakeStage*> fakes;
    int detections = 0;
    bool present = true;
    int frame = 0;
    FrameResult out;
    std::unique_ptr<track::TrackerCore> core;
};

TEST_F(StageRunner, ListOrderIsExecutionOrderAndTimingOrder) {
    build({"c", "a", "b"});
    const FrameResult& first = step();
    EXPECT_EQ(log, (std::vector<std::string>{"c", "a", "b"}));
    EXPECT_EQ(names(first), (std::vector<std::string>{"detect", "c", "a", "b"}));
    for (const auto& t : first.timings) EXPECT_GE(t.ms, 0.0);
    const FrameResult& second = step();
    EXPECT_EQ(names(second), (std::vector<std::string>{"c", "a", "b"}));  // followed: no search
    ASSERT_EQ(second.faces.size(), 1u);
    EXPECT_TRUE(second.faces[0].tracked);
    EXPECT_EQ(second.faces[0].fit_residual, 2.f);   // the last stage wrote last
    EXPECT_EQ(second.faces[0].box.x0, 20.f + 6.f);  // each stage moved the face, two frames of three stages
    const auto listed = core->stages();
    ASSERT_EQ(listed.size(), 5u);
    EXPECT_EQ(listed[0].name, "detect");
    EXPECT_EQ(listed[1].name, "verify");
    EXPECT_EQ(listed[2].name, "c");
    EXPECT_EQ(listed[4].name, "b");
}

TEST_F(StageRunner, AFailingStageDropsTheFaceAndItIsFoundAgain) {
    build({"a", "b", "c"});
    fakes[1]->fail_on = {2};
    const int firstId = step().faces.at(0).id;
    step();
    EXPECT_EQ(detections, 1);
    // Frame 2: b loses the face, c does not run on it, and the detector looks again in the same frame.
    const FrameResult& lost = step();
    EXPECT_EQ(detections, 2);
    EXPECT_EQ(log, (std::vector<std::string>{"a", "b", "a", "b"}));
    EXPECT_TRUE(lost.faces.empty());  // the new face failed at b too (still frame 2)
    const FrameResult& back = step();
    EXPECT_EQ(detections, 3);
    ASSERT_EQ(back.faces.size(), 1u);
    EXPECT_FALSE(back.faces[0].tracked);
    EXPECT_GT(back.faces[0].id, firstId);
    EXPECT_EQ(names(back).front(), "detect");
}

TEST_F(StageRunner, AFaceLeavingIsNotReportedAndIsReDetectedOnReturn) {
    build({"a"});
    step();
    present = false;
    fakes[0]->fail_on = {1, 2};
    EXPECT_TRUE(step().faces.empty());
    EXPECT_TRUE(step().faces.empty());
    present = true;
    fakes[0]->fail_on.clear();
    ASSERT_EQ(step().faces.size(), 1u);
    EXPECT_FALSE(out.faces[0].tracked);
}

TEST_F(StageRunner, AStageThatIsNotAvailableNeverRunsAndLeavesItsFieldsEmpty) {
    build({"a", "-gaze", "b"});
    for (int i = 0; i < 3; ++i) {
        const FrameResult& r = step();
        EXPECT_EQ(log, (std::vector<std::string>{"a", "b"}));
        ASSERT_EQ(r.faces.size(), 1u);
        EXPECT_FALSE(r.faces[0].gaze.has_value());
        const auto n = names(r);
        EXPECT_EQ(std::count(n.begin(), n.end(), "gaze"), 0);
    }
    EXPECT_FALSE(core->stages()[3].available);
}

TEST_F(StageRunner, WithoutAStageThatLocatesTheFaceItIsDetectedEveryFrame) {
    build({"-a"});
    for (int i = 0; i < 3; ++i) {
        const FrameResult& r = step();
        ASSERT_EQ(r.faces.size(), 1u);
        EXPECT_FLOAT_EQ(r.faces[0].confidence, 0.9f);  // the detector's score
        EXPECT_EQ(r.faces[0].box.x0, 20.f);
    }
    EXPECT_EQ(detections, 3);
}

TEST_F(StageRunner, EveryFaceHasItsOwnStateAndResetIdentityReachesIt) {
    build({"a"});
    step();
    step();
    core->resetIdentity();
    step();
    EXPECT_EQ(fakes[0]->seen.runs, 3);
    EXPECT_EQ(fakes[0]->seen.resets, 1);
    core->reset();  // a new stream: a new face with a new state
    step();
    EXPECT_FALSE(out.faces.at(0).tracked);
    EXPECT_EQ(fakes[0]->seen.runs, 1);
    EXPECT_EQ(fakes[0]->seen.resets, 0);
}

TEST_F(StageRunner, TimeThatDoesNotIncreaseCountsAsOneFrameAt30Fps) {
    build({"a"});
    auto at = [&](double t) {
        core->process({pixels.data(), 80, 60, 80, PixelFormat::Gray8}, t, nullptr, out);
        return fakes[0]->dt;
    };
    EXPECT_NEAR(at(10.0), 1.0 / 30, 1e-12);  // the first frame
    EXPECT_NEAR(at(10.5), 0.5, 1e-12);
    EXPECT_NEAR(at(10.5), 1.0 / 30, 1e-12);  // repeated
    EXPECT_NEAR(at(9.0), 1.0 / 30, 1e-12);   // backwards
    EXPECT_NEAR(at(std::nan("")), 1.0 / 30, 1e-12);
    EXPECT_NEAR(at(11.0), 0.5, 1e-12);  // measured from the last good time
}

TEST_F(StageRunner, CallerBoxesReplaceTheDetector) {
    build({"a"});
    const std::vector<Box> boxes = {{5.f, 5.f, 35.f, 35.f}};
    const FrameResult& r = step(&boxes);
    EXPECT_EQ(detections, 0);
    ASSERT_EQ(r.faces.size(), 1u);
    EXPECT_EQ(r.faces[0].box.x0, 6.f);
    EXPECT_EQ(names(r), (std::vector<std::string>{"a"}));
    const std::vector<Box> none;
    EXPECT_EQ(step(&none).faces.size(), 1u);  // still followed
    EXPECT_EQ(detections, 0);
}

TEST_F(StageRunner, VerificationDropsAFaceTheDetectorNoLongerSees) {
    build({"a"}, 3);
    for (int i = 0; i < 3; ++i) ASSERT_EQ(step().faces.size(), 1u);
    present = false;  // the detector no longer finds it on the crop
    const FrameResult& r = step();
    EXPECT_TRUE(r.faces.empty());
    EXPECT_TRUE(log.empty());                                             // dropped before the stages
    EXPECT_EQ(names(r), (std::vector<std::string>{"detect", "verify"}));  // verified, lost, searched again
}

// A stage that doubts a followed face runs once more in the same frame, with
// the stages before it, from where the first pass left the face; the stages
// after it run once. Each stage's time covers both of its runs.
TEST_F(StageRunner, AStageInDoubtRunsAgainWithTheStagesBeforeIt) {
    build({"a", "b", "c"});
    fakes[1]->doubt_on = {1};
    step();
    EXPECT_EQ(log, (std::vector<std::string>{"a", "b", "c"}));
    FrameResult r = step();
    EXPECT_EQ(log, (std::vector<std::string>{"a", "b", "a", "b", "c"}));
    EXPECT_EQ(names(r), (std::vector<std::string>{"a", "b", "c"}));
    EXPECT_EQ(fakes[0]->seen.runs, 3);              // its state carried from the first pass to the second
    EXPECT_EQ(r.faces.at(0).box.x0, 20.f + 3 + 5);  // three stages, then two again
    step();
    EXPECT_EQ(log, (std::vector<std::string>{"a", "b", "c"}));

    fakes[1]->fail_on = {3};  // lost in the first pass: not run again, but found again by the detector (fresh: run once)
    fakes[1]->doubt_on = {3};
    r = step();
    EXPECT_EQ(log, (std::vector<std::string>{"a", "b", "a", "b"}));
}

// An unsettled face (a stage's answer far from the previous frame's) runs
// again the same way, but is not doubted: no detector check.
TEST_F(StageRunner, AnUnsettledFaceRunsAgainWithoutADetectorCheck) {
    build({"a"}, 30);
    fakes[0]->unsettle_on = {1};
    step();  // 21..61
    const int detectionsBefore = detections;
    FrameResult r = step();
    EXPECT_EQ(log, (std::vector<std::string>{"a", "a"}));
    EXPECT_EQ(names(r), (std::vector<std::string>{"a"}));
    EXPECT_EQ(detections, detectionsBefore);
    EXPECT_TRUE(r.faces.at(0).tracked);
    EXPECT_EQ(r.faces[0].box.x0, 23.f);
    step();
    EXPECT_EQ(log, (std::vector<std::string>{"a"}));
}

// A face a stage doubts (and ran again, above) is checked with the detector in
// the same frame: seen elsewhere, the stages run again from the detection (same
// id, reported as found); seen where it is, or not seen at all, the face stays
// as the second pass left it.
TEST_F(StageRunner, AFaceInDoubtIsCheckedAndRestartsWhereTheDetectorSeesIt) {
    build({"a"}, 30);
    fakes[0]->doubt_on = {2, 3, 4};
    const int id = step().faces.at(0).id;  // the detector's box, 20..60, moved to 21..61
    step();                                // 22..62
    fakes[0]->doubt_jump = 6.f;            // frame 2: the stage slides to 29..69, doubts it, slides again to 36..76
    FrameResult r = step();
    EXPECT_EQ(log, (std::vector<std::string>{"a", "a", "a"}));  // run again, then from the detection
    EXPECT_EQ(detections, 2);
    ASSERT_EQ(r.faces.size(), 1u);
    EXPECT_EQ(r.faces[0].id, id);
    EXPECT_FALSE(r.faces[0].tracked);
    EXPECT_EQ(r.faces[0].box.x0, 21.f);  // the detection, moved once (a fresh face is not run again)
    EXPECT_EQ(names(r), (std::vector<std::string>{"verify", "a"}));

    fakes[0]->doubt_jump = 0.f;  // frame 3: doubted where the detector sees it
    r = step();
    EXPECT_EQ(log, (std::vector<std::string>{"a", "a"}));
    EXPECT_EQ(detections, 3);
    EXPECT_TRUE(r.faces.at(0).tracked);
    EXPECT_EQ(r.faces[0].box.x0, 23.f);

    present = false;  // frame 4: doubted, the detector sees nothing: kept
    fakes[0]->doubt_jump = 12.f;
    r = step();
    EXPECT_EQ(log, (std::vector<std::string>{"a", "a"}));
    ASSERT_EQ(r.faces.size(), 1u);
    EXPECT_EQ(r.faces[0].box.x0, 49.f);
}

// The detection 8 px (0.2 of the 40 px box) across from the face: a periodic check lets it be (a
// turned face's box and YuNet's differ by that much), a check of a face in doubt restarts it.
TEST_F(StageRunner, AFaceInDoubtMustAgreeWithTheDetectorMoreCloselyThanAPeriodicCheck) {
    build({"a"}, 8);
    for (int i = 0; i < 8; ++i) step();  // the stage moves the face a pixel a frame: 28..68 after frame 7
    FrameResult r = step();              // frame 8: checked now and then, kept
    EXPECT_EQ(names(r), (std::vector<std::string>{"verify", "a"}));
    EXPECT_TRUE(r.faces.at(0).tracked);
    EXPECT_EQ(r.faces[0].box.x0, 29.f);

    fakes.clear();
    build({"a"}, 30);
    fakes[0]->doubt_on = {2};
    frame = 0;
    step();                      // 21..61
    step();                      // 22..62
    fakes[0]->doubt_jump = 5.f;  // frame 2: the stage moves it to 28..68 and doubts it (and again to 34..74)
    r = step();
    EXPECT_EQ(log, (std::vector<std::string>{"a", "a", "a"}));  // run again, then from the detection
    EXPECT_FALSE(r.faces.at(0).tracked);
    EXPECT_EQ(r.faces[0].box.x0, 21.f);
}

// The contracts: a stage whose reads no earlier available stage writes is not
// available, and says which; the others are told what the stages before them
// write and estimate.
TEST_F(StageRunner, AStageWhoseReadsNoEarlierStageWritesIsNotAvailable) {
    using pipeline::Field;
    build({"landmarks", "-fit", "gaze", "pose", "late"}, 0,
          {{{}, Field::Landmarks, {3, 4}},
           {Field::Landmarks, Field::Pose},
           {Field::Landmarks | Field::Pose, Field::Gaze},  // its pose's writer is not available
           {Field::Landmarks, Field::Pose | Field::Expression, {7}, true},
           {Field::Pose | Field::Gaze, {}}});  // gaze: its writer could not run
    const auto listed = core->stages();
    EXPECT_TRUE(listed[2].available);
    EXPECT_FALSE(listed[3].available);
    EXPECT_FALSE(listed[4].available);
    EXPECT_EQ(listed[4].detail, "not available: needs pose, which no stage before it writes");
    EXPECT_TRUE(listed[5].available);
    EXPECT_FALSE(listed[6].available);
    EXPECT_EQ(listed[6].detail, "not available: needs gaze, which no stage before it writes");
    step();
    EXPECT_EQ(log, (std::vector<std::string>{"landmarks", "pose"}));
    EXPECT_FALSE(fakes[2]->connected);
    EXPECT_TRUE(fakes[3]->told.written == Field::Landmarks);
    EXPECT_EQ(fakes[3]->told.expressions, (std::vector<int>{3, 4}));
    EXPECT_TRUE(fakes[3]->told.smoothed_expressions.empty());
    EXPECT_EQ(core->estimatedExpressions(), (std::vector<int>{3, 4, 7}));
    // What "pose" provides, as a later stage would be told it.
    pipeline::Upstream after = fakes[3]->told;
    pipeline::provide(fakes[3]->contract(), after);
    EXPECT_TRUE(after.written == (Field::Landmarks | Field::Pose | Field::Expression));
    EXPECT_EQ(after.smoothed_expressions, (std::vector<int>{7}));
}

TEST_F(StageRunner, NullStagesAndDetectorsAreRefused) {
    pipeline::StageList withNull;
    withNull.push_back(nullptr);
    EXPECT_THROW(track::TrackerCore(std::make_unique<FakeDetector>(&detections), std::move(withNull), {}), Error);
    EXPECT_THROW(track::TrackerCore(nullptr, {}, {}), Error);
}

// The calibration stage alone: each ARKit weight through calibrated(), the
// native weights relative to their neutral, a neutral captured from what the
// stage was given (not what it reported), the eyes' look directions left alone.
TEST(CalibrationStage, AppliesTheCalibrationAndCapturesTheNeutralItWasGiven) {
    const auto model = FaceModel::load(test::shippedFaceModel());
    const auto stage = calibration::makeCalibrationStage(model);
    EXPECT_TRUE(stage->contract().reads == pipeline::Field::Expression);
    const auto state = stage->newFaceState();
    const auto smile = static_cast<std::size_t>(arkitIndex("mouthSmileLeft")), look = static_cast<std::size_t>(arkitIndex("eyeLookInLeft"));
    const cv::Mat gray(8, 8, CV_8UC1, cv::Scalar(0));
    const auto& natives = model->expressionNames();
    const auto smileNative = static_cast<std::size_t>(std::find(natives.begin(), natives.end(), "mouthSmile_L") - natives.begin());
    ASSERT_LT(smileNative, natives.size());
    ASSERT_NE(smileNative, 0u);
    const pipeline::FrameInput frame{{}, gray, {}, 1.0 / 30};
    pipeline::FaceTrack face;
    const auto run = [&](float smileWeight) {
        face.result.expression.emplace();
        face.result.expression->native.assign(model->expressionNames().size(), 0.f);
        face.result.expression->native[0] = smileWeight;
        face.result.expression->native[smileNative] = smileWeight;
        face.result.expression->arkit[smile] = smileWeight;
        face.result.expression->arkit[look] = 0.3f;
        EXPECT_EQ(stage->run(frame, face, state.get()), pipeline::Outcome::Ok);
        return *face.result.expression;
    };
    EXPECT_FLOAT_EQ(run(0.2f).arkit[smile], 0.2f);  // no calibration: as given
    Calibration calibration;
    stage->captureNeutral(state.get(), calibration);
    EXPECT_FLOAT_EQ(calibration.shapes[smile].neutral, 0.2f);
    EXPECT_FLOAT_EQ(calibration.shapes[look].neutral, 0.f);  // the look directions keep theirs
    ASSERT_EQ(calibration.native_neutral.size(), model->expressionNames().size());
    EXPECT_FLOAT_EQ(calibration.native_neutral[0], 0.2f);
    calibration.shapes[smile].full = 0.6f;
    stage->setCalibration(calibration, {state.get()});
    EXPECT_FLOAT_EQ(run(0.2f).arkit[smile], 0.f);
    auto w = run(0.4f);
    EXPECT_FLOAT_EQ(w.arkit[smile], 0.5f);         // half way from the neutral to the full
    EXPECT_FLOAT_EQ(w.native[0], 0.2f / 0.8f);     // a native weight: from its neutral to its ARKit shape's full (1 here)
    EXPECT_FLOAT_EQ(w.native[smileNative], 0.5f);  // the smile's own: to the smile's full, as the avatar must move
    EXPECT_FLOAT_EQ(w.arkit[look], 0.3f);
    EXPECT_FLOAT_EQ(run(0.1f).arkit[smile], 0.f);  // below the neutral: clamped
    EXPECT_FLOAT_EQ(run(0.9f).arkit[smile], 1.f);  // beyond the full: clamped
    run(0.4f);
    stage->captureNeutral(state.get(), calibration);  // from the 0.4 given, not the 0.5 reported
    EXPECT_FLOAT_EQ(calibration.shapes[smile].neutral, 0.4f);
    stage->setCalibration(Calibration{}, {state.get()});
    EXPECT_FLOAT_EQ(run(0.6f).arkit[smile], 0.6f);
    calibration.native_neutral.resize(3);  // not the face model's
    EXPECT_THROW(stage->setCalibration(calibration, {state.get()}), Error);
}

TEST(TrackerApi, TakesTheApplicationsOwnDetector) {
    Models models{FaceModel::load(test::shippedFaceModel()), nullptr, nullptr, nullptr, nullptr};
    int calls = 0;
    Tracker tracker(models, {}, std::make_unique<FakeDetector>(&calls));
    EXPECT_EQ(tracker.stages()[0].detail.rfind("fake (none)", 0), 0u) << tracker.stages()[0].detail;
    const std::vector<std::uint8_t> gray = frameWithAFace();
    FrameResult out;
    tracker.process({gray.data(), 80, 60, 80, PixelFormat::Gray8}, 0.0, out);
    EXPECT_EQ(calls, 1);
    ASSERT_EQ(out.faces.size(), 1u);
    EXPECT_EQ(out.faces[0].box.x1, 60.f);
    EXPECT_THROW(Tracker(models, {}, nullptr), Error);

    // The caller's box instead of the detector; the camera's principal point as configured.
    TrackerConfig config;
    config.camera.principal_x_px = 30.0;
    config.camera.principal_y_px = 20.0;
    Tracker boxed(models, config, std::make_unique<FakeDetector>(&calls));
    boxed.process({gray.data(), 80, 60, 80, PixelFormat::Gray8}, 0.0, {{1.f, 2.f, 31.f, 32.f}}, out);
    EXPECT_EQ(calls, 1);
    ASSERT_EQ(out.faces.size(), 1u);
    EXPECT_EQ(out.faces[0].box.y0, 2.f);
    EXPECT_EQ(out.camera.cx, 30.f);
    EXPECT_EQ(out.camera.cy, 20.f);
    EXPECT_EQ(out.camera.width, 80);
    EXPECT_EQ(out.camera.height, 60);
    config.camera.principal_x_px = std::nan("");
    EXPECT_THROW(Tracker(models, config, std::make_unique<FakeDetector>(&calls)), Error);
}

}  // namespace
}  // namespace facetrack
