// The user's calibration as data: its formula, its checks, its JSON profile,
// the guided capture, and a Tracker applying and producing one.

#include "facetrack/calibration.hpp"
#include "facetrack/error.hpp"
#include "facetrack/tracker.hpp"
#include "core/image.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>

namespace facetrack {
namespace {

std::size_t shape(const char* name) { return static_cast<std::size_t>(arkitIndex(name)); }

TEST(Calibration, MapsTheNeutralToZeroAndTheFullExpressionToOne) {
    const ShapeCalibration none;
    for (float w : {0.f, 0.3f, 1.f}) EXPECT_FLOAT_EQ(calibrated(none, w), w);
    ShapeCalibration s{0.2f, 0.6f, 1.f, 0.f};
    EXPECT_FLOAT_EQ(calibrated(s, 0.2f), 0.f);
    EXPECT_FLOAT_EQ(calibrated(s, 0.4f), 0.5f);
    EXPECT_FLOAT_EQ(calibrated(s, 0.6f), 1.f);
    EXPECT_FLOAT_EQ(calibrated(s, 0.1f), 0.f);  // below the neutral
    EXPECT_FLOAT_EQ(calibrated(s, 0.9f), 1.f);  // beyond the full
    s.dead_zone = 0.25f;                        // r = 0.5 -> (0.5 - 0.25) / 0.75
    EXPECT_FLOAT_EQ(calibrated(s, 0.4f), 1.f / 3.f);
    EXPECT_FLOAT_EQ(calibrated(s, 0.29f), 0.f);  // r = 0.225: inside the dead zone
    EXPECT_FLOAT_EQ(calibrated(s, 0.6f), 1.f);
    s.gain = 2.f;
    EXPECT_FLOAT_EQ(calibrated(s, 0.4f), 2.f / 3.f);
    EXPECT_FLOAT_EQ(calibrated(s, 0.5f), 1.f);  // capped
}

TEST(Calibration, RefusesValuesOutOfRangeNamingTheShape) {
    EXPECT_NO_THROW(validate(Calibration{}));
    const auto refused = [](void (*edit)(Calibration&), const char* says) {
        Calibration c;
        edit(c);
        try {
            validate(c);
            ADD_FAILURE() << "accepted: " << says;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
        }
    };
    refused([](Calibration& c) { c.shapes[shape("jawOpen")].neutral = 1.f; }, "jawOpen neutral");
    refused([](Calibration& c) { c.shapes[shape("jawOpen")].neutral = -0.1f; }, "jawOpen neutral");
    refused([](Calibration& c) { c.shapes[shape("mouthPucker")].full = 0.f; }, "mouthPucker full");
    refused([](Calibration& c) { c.shapes[shape("mouthPucker")].full = 1.5f; }, "mouthPucker full");
    refused([](Calibration& c) { c.shapes[shape("browInnerUp")].gain = 0.f; }, "browInnerUp gain");
    refused([](Calibration& c) { c.shapes[shape("browInnerUp")].gain = std::nanf(""); }, "browInnerUp gain");
    refused([](Calibration& c) { c.shapes[shape("cheekPuff")].dead_zone = 1.f; }, "cheekPuff dead_zone");
    refused([](Calibration& c) { c.native_neutral = {0.1f, 1.2f}; }, "native_neutral");
    refused([](Calibration& c) { c.identity = {0.5f, INFINITY}; }, "identity");
    refused([](Calibration& c) { c.identity = {0.5f, -11.f}; }, "identity");
}

TEST(Calibration, JsonReadsBackExactlyAndLeavesDefaultsOut) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    Calibration c;
    for (auto& s : c.shapes) {
        s.neutral = 0.5f * u(rng);
        s.full = s.neutral + (1.f - s.neutral) * (0.05f + 0.95f * u(rng));
        s.gain = 0.5f + 2.f * u(rng);
        s.dead_zone = 0.2f * u(rng);
    }
    c.shapes[shape("tongueOut")] = {};
    for (int k = 0; k < 53; ++k) c.native_neutral.push_back(0.3f * u(rng));
    for (int k = 0; k < 100; ++k) c.identity.push_back(4.f * u(rng) - 2.f);
    const std::string json = toJson(c);
    EXPECT_EQ(calibrationFromJson(json), c);
    EXPECT_EQ(toJson(calibrationFromJson(json)), json);
    EXPECT_EQ(json.find("tongueOut"), std::string::npos);  // at its defaults
    EXPECT_EQ(calibrationFromJson(toJson(Calibration{})), Calibration{});
    // Hand-written: the shortest text of a float reads back as that float.
    Calibration edited;
    edited.shapes[shape("mouthSmileLeft")].full = 0.6f;
    const std::string text = toJson(edited);
    EXPECT_NE(text.find("\"full\": 0.6"), std::string::npos) << text;
    EXPECT_EQ(calibrationFromJson(R"({"format": "facetrack-calibration", "version": 1,
                                     "shapes": {"mouthSmileLeft": {"full": 0.6}}})"),
              edited);
}

TEST(Calibration, ABadOrTruncatedProfileIsAClearError) {
    Calibration c;
    c.shapes[shape("browInnerUp")] = {0.05f, 0.4f, 1.5f, 0.1f};
    const std::string json = toJson(c);
    const auto says = [](const std::string& text, const char* what) {
        try {
            calibrationFromJson(text);
            ADD_FAILURE() << "accepted: " << text;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    };
    for (std::size_t cut : {std::size_t{0}, std::size_t{1}, json.size() / 3, json.size() / 2, json.size() - 3}) {
        says(json.substr(0, cut), "not valid JSON");
    }
    says("[1, 2]", "not a facetrack-calibration file");
    says(R"({"format": "facetrack-calibration", "version": 2})", "version 2");
    says(R"({"format": 3, "version": 1})", "not a facetrack-calibration file");
    says(R"({"format": "facetrack-calibration", "version": 1, "shapes": {"smile": {}}})", "unknown shape 'smile'");
    says(R"({"format": "facetrack-calibration", "version": 1, "shapes": {"jawOpen": {"max": 1}}})", "unknown field 'jawOpen.max'");
    says(R"({"format": "facetrack-calibration", "version": 1, "shapes": {"jawOpen": {"full": "1"}}})", "jawOpen.full must be a number");
    says(R"({"format": "facetrack-calibration", "version": 1, "shapes": {"jawOpen": {"full": 0}}})", "jawOpen full must be in");
    says(R"({"format": "facetrack-calibration", "version": 1, "identity": [1, null]})", "identity[1] must be a number");
    says(R"({"format": "facetrack-calibration", "version": 1, "colour": "red"})", "unknown field 'colour'");

    const std::string dir = ::testing::TempDir() + "facetrack_profile_test";
    std::filesystem::remove_all(dir);
    const std::string path = dir + "/sub/profile.json";
    saveCalibration(c, path);  // makes its folder
    EXPECT_EQ(loadCalibration(path), c);
    std::ofstream(path, std::ios::trunc) << json.substr(0, json.size() / 2);
    try {
        loadCalibration(path);
        ADD_FAILURE() << "a truncated file was read";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
    EXPECT_THROW(loadCalibration(dir + "/none.json"), Error);
    std::filesystem::remove_all(dir);
}

TEST(Calibration, TheDefaultProfileFollowsXdgConfigHome) {
    const char* before = std::getenv("XDG_CONFIG_HOME");
    const std::string saved = before ? before : "";
    setenv("XDG_CONFIG_HOME", "/tmp/xdg", 1);
    EXPECT_EQ(defaultProfilePath(), "/tmp/xdg/facetrack/profile.json");
    unsetenv("XDG_CONFIG_HOME");
    EXPECT_NE(defaultProfilePath().find("/.config/facetrack/profile.json"), std::string::npos);
    if (before) setenv("XDG_CONFIG_HOME", saved.c_str(), 1);
}

ExpressionResult weights(std::initializer_list<std::pair<const char*, float>> values, float look = 0.f) {
    ExpressionResult e;
    e.native.assign(4, 0.1f);
    for (const auto& [name, w] : values) e.arkit[shape(name)] = w;
    e.arkit[shape("eyeLookOutLeft")] = look;
    return e;
}

TEST(CalibrationCapture, TakesTheNeutralsMeanAndEachPromptsHighValues) {
    Calibration base;
    base.shapes[shape("mouthPucker")].gain = 1.5f;  // not measured: kept
    base.identity = {0.25f};
    CalibrationCapture capture(base);
    EXPECT_THROW(capture.result(), Error);  // no neutral yet
    capture.add("neutral", weights({{"mouthSmileLeft", 0.1f}, {"browInnerUp", 0.02f}}, 0.4f));
    capture.add("neutral", weights({{"mouthSmileLeft", 0.2f}, {"browInnerUp", 0.04f}}, 0.4f));
    for (int i = 0; i <= 10; ++i) capture.add("smile", weights({{"mouthSmileLeft", 0.05f * static_cast<float>(i)}}));
    // Raised brows that hardly move the shape: not taken as the user's full.
    for (int i = 0; i < 5; ++i) capture.add("brows_up", weights({{"browInnerUp", 0.1f}}));
    EXPECT_EQ(capture.frames("smile"), 11);
    EXPECT_THROW(capture.add("yawn", weights({})), Error);
    const Calibration c = capture.result();
    EXPECT_FLOAT_EQ(c.shapes[shape("mouthSmileLeft")].neutral, 0.15f);
    EXPECT_FLOAT_EQ(c.shapes[shape("mouthSmileLeft")].full, 0.45f);  // the 90th percentile of 0 .. 0.5
    EXPECT_FLOAT_EQ(c.shapes[shape("browInnerUp")].neutral, 0.03f);
    EXPECT_FLOAT_EQ(c.shapes[shape("browInnerUp")].full, 1.f);
    EXPECT_FLOAT_EQ(c.shapes[shape("eyeLookOutLeft")].neutral, 0.f);  // the eyes may look anywhere
    EXPECT_FLOAT_EQ(c.shapes[shape("mouthPucker")].gain, 1.5f);
    EXPECT_EQ(c.identity, base.identity);
    EXPECT_EQ(c.native_neutral, std::vector<float>(4, 0.1f));
}

#define FACETRACK_REQUIRE_PIPELINE()                                                                                \
    do {                                                                                                            \
        FACETRACK_REQUIRE_SHARED();                                                                                 \
        if (!std::filesystem::exists(test::sourceDir() + "/models/landmarks_lbf.ftm")) GTEST_SKIP() << "no models"; \
    } while (0)

// A Tracker hands back the calibration it was given, and its identity is the
// user's from the first frame: no estimation window.
TEST(TrackerCalibration, AppliesWhatItIsGivenAndHandsItBack) {
    FACETRACK_REQUIRE_PIPELINE();
    const auto frames = test::clipFrames(3);
    Models models = Models::loadDefault();
    Tracker tracker(models);
    EXPECT_EQ(tracker.calibration(), Calibration{});
    Calibration c;
    for (auto& s : c.shapes) s = {0.02f, 0.5f, 1.2f, 0.05f};
    c.identity.assign(static_cast<std::size_t>(models.face->identityCount()), 0.f);
    c.identity[0] = 0.5f;
    Calibration wrong = c;
    wrong.identity.pop_back();
    EXPECT_THROW(tracker.setCalibration(wrong), Error);
    wrong = c;
    wrong.native_neutral = {0.1f};
    EXPECT_THROW(tracker.setCalibration(wrong), Error);
    EXPECT_EQ(tracker.calibration(), Calibration{});  // unchanged
    tracker.setCalibration(c);
    EXPECT_EQ(tracker.calibration(), c);
    // A peer with the same identity and no other calibration: each reported weight is calibrated() of the peer's.
    Calibration identityOnly;
    identityOnly.identity = c.identity;
    Tracker peer(models);
    peer.setCalibration(identityOnly);
    FrameResult mine, peers;
    for (std::size_t i = 0; i < frames.size(); ++i) {
        tracker.process(core::viewOf(frames[i]), i / 25.0, mine);
        peer.process(core::viewOf(frames[i]), i / 25.0, peers);
    }
    ASSERT_EQ(mine.faces.size(), 1u);
    ASSERT_EQ(peers.faces.size(), 1u);
    const FaceResult& face = mine.faces[0];
    EXPECT_TRUE(face.identity_calibrated);  // from the first frame
    EXPECT_EQ(face.identity, c.identity);
    ASSERT_TRUE(face.expression && peers.faces[0].expression);
    int changed = 0;
    for (std::size_t k = 0; k < face.expression->arkit.size(); ++k) {
        const float w = peers.faces[0].expression->arkit[k];
        EXPECT_FLOAT_EQ(face.expression->arkit[k], calibrated(c.shapes[k], w)) << arkitNames()[k];
        changed += face.expression->arkit[k] != w;
    }
    EXPECT_GT(changed, 5);
    tracker.resetIdentity();
    EXPECT_TRUE(tracker.calibration().identity.empty());
}

}  // namespace
}  // namespace facetrack
