// The gaze stage: eye patches, forests, the model file, the MAP fit on ideal
// maps, and the whole stage on synthetic renders of known gaze (blink, wink,
// both eyes closed, an eye at the frame's border).

#include "common/finite_result.hpp"
#include "common/synthetic_face.hpp"
#include "gaze/eye_model_data.hpp"
#include "gaze/eye_patch.hpp"
#include "gaze/forest_training.hpp"
#include "gaze/gaze_fit.hpp"
#include "gaze/gaze_stage.hpp"
#include "gaze/iris_net.hpp"

#include "core/binary_io.hpp"
#include "core/image.hpp"
#include "facetrack/facetrack.hpp"
#include "model/internals.hpp"
#include "test_support.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <cstring>
#include <fstream>
#include <numeric>
#include <set>

namespace facetrack {
namespace {

using namespace gaze;
constexpr float kDeg = 3.14159265f / 180.f;
/// On single renders of a frontal face: the targets are 3 degrees mean and 6
/// p95 (eval-gaze, 400 renders: 2.15 / 5.16 now); the worst of these 8 eyes
/// read 3.5 when the bound was set, so 7 catches a regression of the eyeballs'
/// placement (without the corner cascade: 15), not only a flipped axis.
constexpr double kRenderGazeToleranceDeg = 7.0;

TEST(EyePatch, PutsTheCornersAtFixedPointsAndMirrorsTheLeftEye) {
    cv::Mat gray(200, 300, CV_8U, cv::Scalar(100));
    cv::circle(gray, {120, 90}, 3, cv::Scalar(250), -1);  // a bright dot near the outer corner of a right eye
    EyePatch p;
    ASSERT_TRUE(cutEyePatch(gray, {110, 92}, {150, 84}, false, p));
    const Point2 outer = toPatch(p, {110, 92}), inner = toPatch(p, {150, 84});
    EXPECT_NEAR(outer.x, kOuterX, 1e-3f);
    EXPECT_NEAR(outer.y, kCornerY, 1e-3f);
    EXPECT_NEAR(inner.x, kInnerX, 1e-3f);
    EXPECT_NEAR(inner.y, kCornerY, 1e-3f);
    const Point2 back = toImage(p, toPatch(p, {123.f, 77.f}));
    EXPECT_NEAR(back.x, 123.f, 1e-3f);
    EXPECT_NEAR(back.y, 77.f, 1e-3f);
    // Normalised: zero mean; the dot is bright and on the outer (left) side.
    EXPECT_NEAR(cv::mean(p.pixels)[0], 0.0, 1e-4);
    cv::Point brightest;
    cv::minMaxLoc(p.pixels, nullptr, nullptr, nullptr, &brightest);
    EXPECT_LT(brightest.x, kPatchWidth / 2);
    // The subject's left eye (outer corner on the image's right) is mirrored: its outer corner lands on the left too.
    EXPECT_TRUE(cutEyePatch(gray, {150, 84}, {110, 92}, true, p));
    EXPECT_NEAR(toPatch(p, {150, 84}).x, kOuterX, 1e-3f);
    EXPECT_LT(p.patch_from_image(0, 0) * p.patch_from_image(1, 1) - p.patch_from_image(0, 1) * p.patch_from_image(1, 0), 0.f);
    // No eye to cut.
    EXPECT_FALSE(cutEyePatch(gray, {110, 92}, {110.5f, 92}, false, p));
    EXPECT_FALSE(cutEyePatch(gray, {NAN, 92}, {150, 84}, false, p));
    // An eye at the frame's border: the border repeats, nothing is read outside.
    EXPECT_TRUE(cutEyePatch(gray, {-20, 5}, {15, -3}, false, p));
    EXPECT_TRUE(cv::checkRange(p.pixels));
}

TEST(EyePatch, AnEyeCrossingTheBorderReadsTheRepeatedBorder) {
    // The same eye cut from the frame (edge reads clamped) and from the frame padded by its repeated
    // edges (every read inside): one patch. An eye wholly inside reads the same with and without the padding.
    // Where the CPU has AVX2 a patch inside the frame is cut by gathers, one crossing its border point
    // by point: this compares the two ways too.
    cv::Mat gray(120, 160, CV_8U), padded;
    cv::randu(gray, 0, 256);
    constexpr int kPad = 40;
    cv::copyMakeBorder(gray, padded, kPad, kPad, kPad, kPad, cv::BORDER_REPLICATE);
    for (const auto& [outer, inner] : {std::pair<Point2, Point2>{{-12.3f, 7.6f}, {21.4f, -2.2f}},
                                       {{139.1f, 104.7f}, {171.5f, 118.2f}},
                                       {{60.4f, 50.9f}, {95.2f, 47.3f}}}) {
        EyePatch cut, fromPadded;
        ASSERT_TRUE(cutEyePatch(gray, outer, inner, false, cut));
        ASSERT_TRUE(cutEyePatch(padded, {outer.x + kPad, outer.y + kPad}, {inner.x + kPad, inner.y + kPad}, false, fromPadded));
        double largest = 0.0;
        cv::minMaxLoc(cv::abs(cut.pixels - fromPadded.pixels), nullptr, &largest);
        EXPECT_LT(largest, 1e-3) << "eye at (" << outer.x << ", " << outer.y << ")";
        EXPECT_GT(cv::norm(cut.pixels), 10.0);  // a textured patch, not a flat one
    }
}

/// A one-tree forest of depth 1 whose two leaves both hold `offsets`.
PatchForest constantCornerForest(const std::array<float, 4>& offsets) {
    PatchForest f;
    f.depth = 1;
    f.outputs = 4;
    f.splits.resize(1);
    f.leaves.assign(offsets.begin(), offsets.end());
    f.leaves.insert(f.leaves.end(), offsets.begin(), offsets.end());
    return f;
}

TEST(EyeCorners, EachStageMovesTheCornersByItsReadingAndReCuts) {
    cv::Mat gray(200, 300, CV_8U, cv::Scalar(100));
    EyePatch patch, scratch;
    // A level right eye 56 px wide: 2 frame pixels per patch pixel.
    ASSERT_TRUE(cutEyePatch(gray, {100, 50}, {156, 50}, false, patch));
    EyeModelData model;
    auto c = eyeCorners(model, gray, patch, scratch);  // no stages: where the patch was cut
    EXPECT_NEAR(c[0].x, 100.f, 1e-3f);
    EXPECT_NEAR(c[1].x, 156.f, 1e-3f);
    model.corner_stages.push_back(constantCornerForest({1.f, 0.5f, -1.f, 0.f}));
    c = eyeCorners(model, gray, patch, scratch);
    EXPECT_NEAR(c[0].x, 102.f, 1e-3f);
    EXPECT_NEAR(c[0].y, 51.f, 1e-3f);
    EXPECT_NEAR(c[1].x, 154.f, 1e-3f);
    EXPECT_NEAR(c[1].y, 50.f, 1e-3f);
    // A second stage reads a patch re-cut at the first one's corners (52 px wide: 52 / 28 px per patch pixel).
    model.corner_stages.push_back(constantCornerForest({0.f, 0.f, 1.f, 0.f}));
    c = eyeCorners(model, gray, patch, scratch);
    EXPECT_NEAR(c[0].x, 102.f, 1e-3f);
    EXPECT_NEAR(c[1].x, 154.f + 52.f / kEyeWidth, 1e-3f);
    // The subject's left eye is mirrored: +x in its patch is towards the nose, the image's left.
    ASSERT_TRUE(cutEyePatch(gray, {156, 50}, {100, 50}, true, patch));
    model.corner_stages.resize(1);
    c = eyeCorners(model, gray, patch, scratch);
    EXPECT_NEAR(c[0].x, 154.f, 1e-3f);
    EXPECT_NEAR(c[1].x, 102.f, 1e-3f);
}

TEST(PatchForest, TrainingLearnsAPixelRuleAndEvaluatesIt) {
    // Class 1 where the pixel is brighter than its right neighbour, else 0.
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    std::vector<cv::Mat> patches;
    std::vector<PatchSample> samples;
    std::vector<float> targets;
    for (int p = 0; p < 40; ++p) {
        cv::Mat m(kPatchHeight, kPatchWidth, CV_32F);
        for (int y = 0; y < m.rows; ++y)
            for (int x = 0; x < m.cols; ++x) m.at<float>(y, x) = u(rng);
        patches.push_back(m);
        for (int k = 0; k < 200; ++k) {
            const int x = static_cast<int>((u(rng) + 1.f) * 18.f) + 1, y = static_cast<int>((u(rng) + 1.f) * 12.f) + 1;
            samples.push_back({p, x, y});
            const bool brighter = m.at<float>(y, x) > m.at<float>(y, x + 1);
            targets.push_back(brighter ? 0.f : 1.f);
            targets.push_back(brighter ? 1.f : 0.f);
        }
    }
    ForestTrainingOptions o;
    o.trees = 4;
    o.depth = 3;
    o.candidates = 300;
    o.draw = [](std::mt19937& r) {
        std::uniform_int_distribution<int> d(-2, 2);
        PatchFeature f;
        f.ax = static_cast<std::int8_t>(d(r)), f.ay = static_cast<std::int8_t>(d(r));
        f.bx = static_cast<std::int8_t>(d(r)), f.by = static_cast<std::int8_t>(d(r));
        return f;
    };
    const PatchForest forest = trainPatchForest(patches, samples, targets, 2, o);
    EXPECT_NO_THROW(forest.validate("test forest"));
    EXPECT_EQ(forest.treeCount(), 4);
    int correct = 0;
    for (std::size_t i = 0; i < samples.size(); ++i) {
        float p[2];
        forest.evaluate(patches[static_cast<std::size_t>(samples[i].patch)], samples[i].x, samples[i].y, p);
        EXPECT_NEAR(p[0] + p[1], 1.f, 1e-4f);
        correct += (p[1] > p[0]) == (targets[2 * i + 1] > 0.5f);
    }
    EXPECT_GT(correct, static_cast<int>(0.97 * samples.size()));
    EXPECT_THROW(trainPatchForest(patches, {}, {}, 2, o), Error);
}

TEST(PatchForest, APaddedPatchGivesWhatClampedReadsGiveAtEveryPixel) {
    // Random tests of every kind reaching 8 px, at every anchor of a patch, edges included (where reads are clamped).
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    std::uniform_int_distribution<int> offset(-kPixelTestReach, kPixelTestReach), kind(0, 3);
    PatchForest forest;
    forest.depth = 6;
    forest.outputs = 3;
    forest.splits.resize(5 * static_cast<std::size_t>(forest.splitsPerTree()));
    for (PatchFeature& f : forest.splits) {
        f.kind = static_cast<std::uint8_t>(kind(rng));
        f.ax = static_cast<std::int8_t>(offset(rng)), f.ay = static_cast<std::int8_t>(offset(rng));
        f.bx = static_cast<std::int8_t>(offset(rng)), f.by = static_cast<std::int8_t>(offset(rng));
        f.threshold = f.kind >= PatchFeature::Column ? static_cast<float>(offset(rng) + 20) : 0.3f * u(rng);
    }
    forest.leaves.resize(5 * static_cast<std::size_t>(forest.leavesPerTree()) * 3);
    for (float& v : forest.leaves) v = u(rng);
    ASSERT_NO_THROW(forest.validate("test forest"));
    EXPECT_LE(forest.reach(), kPixelTestReach);
    cv::Mat patch(kPatchHeight, kPatchWidth, CV_32F), padded;
    for (int y = 0; y < patch.rows; ++y)
        for (int x = 0; x < patch.cols; ++x) patch.at<float>(y, x) = u(rng);
    padPatch(patch, kPixelTestReach, padded);
    std::set<std::vector<float>> outputs;
    for (int y = 0; y < patch.rows; ++y) {
        for (int x = 0; x < patch.cols; ++x) {
            std::vector<float> clamped(3), fast(3);
            forest.evaluate(patch, x, y, clamped.data());
            forest.evaluatePadded(padded, kPixelTestReach, x, y, fast.data());
            ASSERT_EQ(clamped, fast) << "at (" << x << ", " << y << ")";
            outputs.insert(fast);
        }
    }
    EXPECT_GT(outputs.size(), 100u);  // the anchors reach many leaves: the comparison is not of one constant
}

TEST(EyeModelFile, RoundTripsAndRejectsDamage) {
    FACETRACK_REQUIRE_EYE_MODEL();
    const std::string shipped = test::sourceDir() + "/models/eye_model.ftm";
    const EyeModelData m = readEyeModel(shipped);
    EXPECT_EQ(m.pixels.outputs, kPixelClasses);
    EXPECT_GT(m.open_aperture, m.closed_aperture);
    EXPECT_FALSE(m.provenance.empty());
    const std::string copy = test::tempPath("eyes.ftm");
    writeEyeModel(copy, m);
    const EyeModelData back = readEyeModel(copy);
    EXPECT_EQ(back.pixels.leaves, m.pixels.leaves);
    EXPECT_EQ(back.aperture.leaves, m.aperture.leaves);
    ASSERT_EQ(back.pixels.splits.size(), m.pixels.splits.size());
    EXPECT_EQ(0, std::memcmp(back.pixels.splits.data(), m.pixels.splits.data(), m.pixels.splits.size() * sizeof(PatchFeature)));
    EXPECT_EQ(back.open_aperture, m.open_aperture);
    EXPECT_EQ(back.closed_aperture, m.closed_aperture);
    EXPECT_EQ(back.provenance, m.provenance);
    EXPECT_EQ(back.open_map_scale, m.open_map_scale);
    EXPECT_EQ(back.open_map_offset, m.open_map_offset);
    EXPECT_EQ(back.net_map_radius, m.net_map_radius);
    ASSERT_EQ(back.corner_stages.size(), m.corner_stages.size());
    for (std::size_t k = 0; k < m.corner_stages.size(); ++k) EXPECT_EQ(back.corner_stages[k].leaves, m.corner_stages[k].leaves);

    const auto expectError = [&](const std::string& path, const std::string& words) {
        try {
            EyeModel::load(path);
            ADD_FAILURE() << "a damaged eye model loaded";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
        }
    };
    {
        std::fstream f(copy, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(1000);
        f.put('\x55');
    }
    expectError(copy, "checksum");
    std::filesystem::resize_file(copy, 500);
    expectError(copy, "truncated");
    expectError(test::tempPath("no_such_eyes.ftm"), "eye model");
    EyeModelData bad = m;
    bad.pixels.leaves.pop_back();
    EXPECT_THROW(writeEyeModel(copy, bad), Error);
    bad = m;
    bad.closed_aperture = bad.open_aperture + 0.1f;
    EXPECT_THROW(writeEyeModel(copy, bad), Error);
    bad = m;
    bad.corner_stages.push_back(constantCornerForest({0, 0, 0, 0}));
    bad.corner_stages.back().outputs = 2;  // a corner stage reads four numbers
    bad.corner_stages.back().leaves.resize(4);
    EXPECT_THROW(writeEyeModel(copy, bad), Error);
    bad.corner_stages.assign(kMaxCornerStages + 1, constantCornerForest({0, 0, 0, 0}));
    EXPECT_THROW(writeEyeModel(copy, bad), Error);
    bad = m;
    bad.pixels.splits.front() = PatchFeature{0, 0, kPixelTestReach + 1, 0};  // a pixel test reaching past the padding
    EXPECT_THROW(writeEyeModel(copy, bad), Error);
    for (const float scale : {0.f, -1.f, std::nanf("")}) {
        bad = m;
        bad.open_map_scale = scale;
        EXPECT_THROW(writeEyeModel(copy, bad), Error) << scale;
    }
    bad = m;
    bad.open_map_offset = std::nanf("");
    EXPECT_THROW(writeEyeModel(copy, bad), Error);
    bad = m;
    bad.net_map_radius = kMaxNetMapRadius + 1;
    EXPECT_THROW(writeEyeModel(copy, bad), Error);
    std::filesystem::remove(copy);
}

/// The fixture net scores each cell by its own patch pixel (2i, 2j) alone, (0, 0, 4 v):
/// P(iris) = e^(4v) / (2 + e^(4v)), P(open) = (1 + e^(4v)) / (2 + e^(4v)).
TEST(IrisNet, ReadsEachRegionCellFromItsOwnPatchPixel) {
    IrisNet net(test::fixtureBytes("iris_net_fixture.onnx"), "the fixture");
    cv::Mat left(kPatchHeight, kPatchWidth, CV_32F), right(kPatchHeight, kPatchWidth, CV_32F);
    for (int y = 0; y < kPatchHeight; ++y)
        for (int x = 0; x < kPatchWidth; ++x) {
            left.at<float>(y, x) = 0.02f * static_cast<float>(x) - 0.4f;
            right.at<float>(y, x) = 0.5f - 0.03f * static_cast<float>(y);
        }
    const PatchRegion r = kClassifiedRegion;
    std::array<cv::Mat, 2> iris, open;
    for (auto* maps : {&iris, &open})
        for (cv::Mat& m : *maps) m = cv::Mat(r.rows(), r.columns(), CV_32F, cv::Scalar(-1.f));
    net.classify({&left, &right}, {&iris[0], &iris[1]}, {&open[0], &open[1]});
    for (int e = 0; e < 2; ++e)
        for (int j = 0; j < r.rows(); ++j)
            for (int i = 0; i < r.columns(); ++i) {
                const float v = (e == 0 ? left : right).at<float>(r.y(j), r.x(i));
                const float k = std::exp(4.f * v);
                EXPECT_NEAR(iris[e].at<float>(j, i), k / (2.f + k), 1e-5f) << "eye " << e << " cell " << i << ", " << j;
                EXPECT_NEAR(open[e].at<float>(j, i), (1.f + k) / (2.f + k), 1e-5f);
            }
    // An eye that was not cut is left alone.
    iris[1].setTo(-1.f);
    net.classify({&left, nullptr}, {&iris[0], &iris[1]}, {&open[0], &open[1]});
    EXPECT_EQ(iris[1].at<float>(0, 0), -1.f);
    // The maps the fit reads: the net's, box-smoothed by the model's radius; an eye not cut is left alone.
    EyeModelData model;
    model.net_map_radius = 1;
    std::array<cv::Mat, 2> smoothIris = {iris[0].clone(), iris[1].clone()}, smoothOpen = {open[0].clone(), open[1].clone()};
    classifyByNet(model, net, {&left, nullptr}, {&smoothIris[0], &smoothIris[1]}, {&smoothOpen[0], &smoothOpen[1]});
    EXPECT_GT(cv::norm(smoothIris[0] - iris[0], cv::NORM_INF), 1e-3);  // the left patch's ramp: smoothing shows at its borders
    boxSmooth(iris[0], 1);
    boxSmooth(open[0], 1);
    EXPECT_NEAR(cv::norm(smoothIris[0] - iris[0], cv::NORM_INF), 0.0, 1e-6);
    EXPECT_NEAR(cv::norm(smoothOpen[0] - open[0], cv::NORM_INF), 0.0, 1e-6);
    EXPECT_EQ(smoothIris[1].at<float>(0, 0), -1.f);
    EXPECT_THROW(IrisNet("not an onnx file", "junk"), Error);
    // A net of the wrong output size: the cascade's parity net (7 outputs for a 64 px patch) does not run on eye patches.
    EXPECT_THROW(IrisNet(test::fixtureBytes("cnn_parity.onnx"), "the cascade's net"), Error);
}

TEST(OpenMap, ItsLidGapIsTheOpenRowsOverTheEyeWidthOnTheModelsScale) {
    // An eye open over rows 3..7 of the classified grid: 5 cells of kClassifiedRegion.step patch pixels.
    cv::Mat open(kClassifiedRegion.rows(), kClassifiedRegion.columns(), CV_32F, cv::Scalar(0.f));
    open.rowRange(3, 8).setTo(1.f);
    const float gap = 5.f * static_cast<float>(kClassifiedRegion.step) / kEyeWidth;
    EXPECT_NEAR(openMapGap(open), gap, 1e-6f);
    EyeModelData model;
    EXPECT_NEAR(openMapAperture(model, open), gap, 1e-6f);  // the pixel forest's map: as read
    model.open_map_scale = 0.65f;
    model.open_map_offset = 0.09f;
    EXPECT_NEAR(openMapAperture(model, open), 0.65f * gap + 0.09f, 1e-6f);
    // Only the columns at 35, 50 and 65 % of the eye count: an open cell elsewhere changes nothing.
    open.col(0).setTo(1.f);
    EXPECT_NEAR(openMapGap(open), gap, 1e-6f);
}

TEST(OpenMap, TheBoxSpreadsACellOverItsNeighboursAndRepeatsTheBorder) {
    const int rows = kClassifiedRegion.rows(), columns = kClassifiedRegion.columns();
    cv::Mat map(rows, columns, CV_32F, cv::Scalar(0.f));
    map.at<float>(4, 7) = 9.f;
    boxSmooth(map, 1);
    for (int y = 0; y < rows; ++y)
        for (int x = 0; x < columns; ++x)
            EXPECT_FLOAT_EQ(map.at<float>(y, x), std::abs(y - 4) <= 1 && std::abs(x - 7) <= 1 ? 1.f : 0.f) << y << ", " << x;
    // A corner cell counts in its own box four times (its row and column repeated), an edge cell twice.
    map.setTo(0.f);
    map.at<float>(0, 0) = 9.f;
    boxSmooth(map, 1);
    EXPECT_FLOAT_EQ(map.at<float>(0, 0), 4.f);
    EXPECT_FLOAT_EQ(map.at<float>(0, 1), 2.f);
    EXPECT_FLOAT_EQ(map.at<float>(1, 1), 1.f);
    // A constant map stays, radius 0 changes nothing, a map of another size is an error.
    map.setTo(0.3f);
    boxSmooth(map, 2);
    EXPECT_NEAR(cv::norm(map - 0.3f, cv::NORM_INF), 0.0, 1e-6);
    map.at<float>(2, 2) = 5.f;
    boxSmooth(map, 0);
    EXPECT_EQ(map.at<float>(2, 2), 5.f);
    cv::Mat other(rows + 1, columns, CV_32F, cv::Scalar(0.f));
    EXPECT_THROW(boxSmooth(other, 1), Error);
}

TEST(EyeModelFile, CarriesAnIrisNetAndReadsVersionsOneToThree) {
    FACETRACK_REQUIRE_EYE_MODEL();
    EyeModelData m = readEyeModel(test::sourceDir() + "/models/eye_model.ftm");
    m.iris_net = test::fixtureBytes("iris_net_fixture.onnx");
    const std::string path = test::tempPath("eyes_cnn.ftm");
    m.open_map_scale = 0.65f;  // the net's open map read on the pixel forest's scale
    m.open_map_offset = 0.09f;
    m.net_map_radius = 1;
    writeEyeModel(path, m);
    const EyeModelData withNet = readEyeModel(path);
    EXPECT_EQ(withNet.iris_net, m.iris_net);
    EXPECT_EQ(withNet.open_map_scale, 0.65f);
    EXPECT_EQ(withNet.open_map_offset, 0.09f);
    EXPECT_EQ(withNet.net_map_radius, 1);
    // The stage classifies with it.
    Models models = Models::loadDefault();
    models.eyes = EyeModel::load(path);
    const Tracker tracker(models, TrackerConfig{});
    bool named = false;
    for (const StageInfo& s : tracker.stages()) named = named || (s.name == "gaze" && s.detail.find("iris CNN") != std::string::npos);
    EXPECT_TRUE(named) << "the gaze stage does not say it uses the iris CNN";
    // A broken net is an error when the file is written or read, naming the net.
    EyeModelData bad = m;
    bad.iris_net = "not an onnx file";
    try {
        writeEyeModel(path, bad);
        ADD_FAILURE() << "a broken iris net was written";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("iris net"), std::string::npos) << e.what();
    }
    // Versions 3 (no open-map scale, no net-map box), 2 (no corner stages) and 1 (no iris net
    // either): the payload without its two floats and an int, then its last byte (the stage
    // count, 0), then the empty iris net's length.
    EyeModelData plain = m;
    plain.iris_net.clear();
    plain.corner_stages.clear();
    writeEyeModel(path, plain);
    std::string payload = core::readModelFile(path, kEyeModelMagic, kEyeModelVersion, "eye model");
    for (const std::uint32_t version : {3u, 2u, 1u}) {
        payload.resize(payload.size() - (version == 3   ? 2 * sizeof(float) + sizeof(std::int32_t)
                                         : version == 2 ? 1
                                                        : sizeof(std::uint32_t)));
        core::writeModelFile(path, kEyeModelMagic, version, payload);
        const EyeModelData old = readEyeModel(path);
        EXPECT_TRUE(old.iris_net.empty());
        EXPECT_TRUE(old.corner_stages.empty());
        EXPECT_EQ(old.open_map_scale, 1.f);
        EXPECT_EQ(old.open_map_offset, 0.f);
        EXPECT_EQ(old.net_map_radius, 0);
        EXPECT_EQ(old.pixels.leaves, m.pixels.leaves);
    }
    std::filesystem::remove(path);
}

/// An eye observed perfectly: the classifier's maps drawn from the model itself at `angles`.
struct IdealEye {
    EyePatch patch;
    cv::Mat iris = cv::Mat(kClassifiedRegion.rows(), kClassifiedRegion.columns(), CV_32F);
    cv::Mat open = cv::Mat(iris.size(), CV_32F, cv::Scalar(1.f));
    EyeObservation seen;
};

void drawIdeal(IdealEye& eye, const Eigen::Matrix3f& R, const core::Camera& camera, const Eigen::Vector2f& angles) {
    ProjectedIris p;
    ASSERT_TRUE(projectIris(eye.seen, R, camera, angles, p));
    Eigen::Matrix2f axes;
    axes << p.axis1, p.axis2;
    const Eigen::Matrix2f inverse = axes.inverse();
    for (int y = 0; y < eye.iris.rows; ++y)
        for (int x = 0; x < eye.iris.cols; ++x) {
            const Eigen::Vector2f q(static_cast<float>(kClassifiedRegion.x(x)), static_cast<float>(kClassifiedRegion.y(y)));
            eye.iris.at<float>(y, x) = (inverse * (q - p.centre)).norm() < 1.f ? 1.f : 0.f;
        }
}

/// Both eyes of a face at (R, t), eyes 31 mm either side of the middle, their
/// patches cut from a flat grey frame between corners 14 mm either side of each
/// eye, in front of the eyeball; the maps are left for the test to draw.
void placeEyes(std::array<IdealEye, 2>& eyes, const Eigen::Matrix3f& R, const Eigen::Vector3f& t, const core::Camera& camera) {
    const cv::Mat gray(480, 640, CV_8U, cv::Scalar(128));
    for (int e = 0; e < 2; ++e) {
        IdealEye& eye = eyes[static_cast<std::size_t>(e)];
        const float side = e == 0 ? 1.f : -1.f;
        eye.seen.centre = R * Eigen::Vector3f(side * 31.f, 35.f, 70.f) + t;
        const auto project = [&](const Eigen::Vector3f& head) {
            const Eigen::Vector3f c = R * head + t;
            return Point2{static_cast<float>(camera.fx * c.x() / c.z() + camera.cx),
                          static_cast<float>(camera.fy * c.y() / c.z() + camera.cy)};
        };
        ASSERT_TRUE(cutEyePatch(gray, project({side * 45.f, 35.f, 78.f}), project({side * 17.f, 35.f, 78.f}), e == 0, eye.patch));
        eye.seen.patch = &eye.patch;
        eye.seen.iris = &eye.iris;
        eye.seen.open = &eye.open;
        eye.seen.weight = 1.f;
    }
}

TEST(GazeFit, RecoversKnownGazeFromIdealMapsAndHoldsWhenBothEyesClose) {
    // A face 500 mm away, turned 15 degrees.
    const Eigen::Matrix3f R = (Eigen::Quaternionf(0, 1, 0, 0) * Eigen::AngleAxisf(15 * kDeg, Eigen::Vector3f::UnitY())).toRotationMatrix();
    core::Camera camera;
    camera.fx = camera.fy = 700, camera.cx = 320, camera.cy = 240;
    std::array<IdealEye, 2> eyes;
    placeEyes(eyes, R, Eigen::Vector3f(0, 0, 500), camera);
    const std::array<std::array<float, 2>, 4> cases = {{{0, 0}, {18, -6}, {-20, 12}, {8, -15}}};
    for (const auto& c : cases) {
        // A shared fixation: the right eye 3 degrees more to the left (vergence).
        const GazeAngles truth{Eigen::Vector2f((c[0] - 1.5f) * kDeg, c[1] * kDeg), Eigen::Vector2f((c[0] + 1.5f) * kDeg, c[1] * kDeg)};
        for (int e = 0; e < 2; ++e) drawIdeal(eyes[static_cast<std::size_t>(e)], R, camera, truth[static_cast<std::size_t>(e)]);
        const GazeAngles got = fitGaze({eyes[0].seen, eyes[1].seen}, R, camera, {}, false);
        for (int e = 0; e < 2; ++e) {
            // Within 2 degrees: the maps are sampled on a 2-pixel grid, and the priors pull a little.
            EXPECT_NEAR(got[e].x() / kDeg, truth[e].x() / kDeg, 2.0) << "yaw, eye " << e << ", case " << c[0] << " " << c[1];
            EXPECT_NEAR(got[e].y() / kDeg, truth[e].y() / kDeg, 2.0) << "pitch, eye " << e;
        }
        // One eye closed: it follows the other.
        auto closedLeft = eyes[0].seen;
        closedLeft.weight = 0.f;
        const GazeAngles wink = fitGaze({closedLeft, eyes[1].seen}, R, camera, got, true);
        EXPECT_NEAR(wink[1].x(), got[1].x(), 1.5f * kDeg);
        EXPECT_NEAR(wink[0].y(), got[1].y(), 2.f * kDeg);
        // Both closed: the gaze holds where it was, finite.
        auto closedRight = eyes[1].seen;
        closedRight.weight = 0.f;
        const GazeAngles held = fitGaze({closedLeft, closedRight}, R, camera, got, true);
        for (int e = 0; e < 2; ++e) {
            EXPECT_TRUE(held[e].allFinite());
            EXPECT_EQ(held[e], got[e]);
        }
    }
}

TEST(GazeFit, TheAppearanceTermPutsTheIrisWhereThePatchShowsIt) {
    // The pixel classifier's map says "looking ahead" (as a forest trained on
    // mostly centred irises does for an eye looking aside); the patch shows a
    // dark iris at 18 degrees to the side on a shaded sclera.
    const Eigen::Matrix3f R = Eigen::Quaternionf(0, 1, 0, 0).toRotationMatrix();
    core::Camera camera;
    camera.fx = camera.fy = 700, camera.cx = 320, camera.cy = 240;
    std::array<IdealEye, 2> eyes;
    placeEyes(eyes, R, Eigen::Vector3f(0, 0, 450), camera);
    const GazeAngles truth{Eigen::Vector2f(16.5f * kDeg, -4.f * kDeg), Eigen::Vector2f(19.5f * kDeg, -4.f * kDeg)};
    for (int e = 0; e < 2; ++e) {
        IdealEye& eye = eyes[static_cast<std::size_t>(e)];
        drawIdeal(eye, R, camera, Eigen::Vector2f::Zero());
        eye.iris *= 0.5f;  // diffuse, as a forest's averaged leaves are
        ProjectedIris p;
        ASSERT_TRUE(projectIris(eye.seen, R, camera, truth[static_cast<std::size_t>(e)], p));
        Eigen::Matrix2f axes;
        axes << p.axis1, p.axis2;
        const Eigen::Matrix2f inverse = axes.inverse();
        for (int y = 0; y < kPatchHeight; ++y)
            for (int x = 0; x < kPatchWidth; ++x) {
                const bool iris = (inverse * (Eigen::Vector2f(static_cast<float>(x), static_cast<float>(y)) - p.centre)).norm() < 1.f;
                eye.patch.pixels.at<float>(y, x) = iris ? -1.5f : 0.8f + 0.6f * static_cast<float>(x) / kPatchWidth;
            }
    }
    const auto worstError = [&](const GazeFitSettings& settings) {
        const GazeAngles got = fitGaze({eyes[0].seen, eyes[1].seen}, R, camera, {}, false, settings);
        double worst = 0;
        for (std::size_t e = 0; e < 2; ++e) worst = std::max(worst, static_cast<double>((got[e] - truth[e]).norm() / kDeg));
        return worst;
    };
    GazeFitSettings mapOnly;
    mapOnly.pixel_sigma = 0.f;
    const double withoutAppearance = worstError(mapOnly), withAppearance = worstError(GazeFitSettings{});
    std::printf("worst error from a map centred ahead: %.2f deg without the appearance term, %.2f with it\n", withoutAppearance,
                withAppearance);
    EXPECT_GT(withoutAppearance, 8.0) << "the map alone should hold the gaze near ahead";
    EXPECT_LT(withAppearance, 2.5) << "the patch's iris should win over the map";
}

TEST(GazeWeights, BlinkAndWideFromOpenness) {
    EXPECT_EQ(blinkWeight(1.f), 0.f);
    EXPECT_EQ(blinkWeight(0.f), 1.f);
    EXPECT_NEAR(blinkWeight(0.525f), 0.5f, 1e-5f);
    EXPECT_EQ(wideWeight(1.f), 0.f);
    EXPECT_NEAR(wideWeight(1.25f), 0.5f, 1e-5f);
}

/// The expected lid gap when looking down comes from the face model's eyeLookDown shapes.
TEST(LidsFollowingGaze, TheFaceModelsLidsCloseAsItsEyesLookDown) {
    if (!std::filesystem::exists(test::sourceDir() + "/models/face_model.ftm")) GTEST_SKIP() << "models/face_model.ftm missing";
    const auto model = FaceModel::loadDefault();
    const LidsFollowingGaze lids(*model);
    EXPECT_NEAR(lids.share(0.f), 1.f, 1e-6f);
    EXPECT_NEAR(lids.share(10.f), 1.f, 1e-6f) << "looking up is not a narrower eye";
    for (float pitch = 0.f; pitch > -40.f; pitch -= 1.f) EXPECT_LE(lids.share(pitch - 1.f), lids.share(pitch) + 1e-6f) << pitch;
    EXPECT_NEAR(lids.share(-40.f), lids.share(-kLookDownFullDeg), 1e-6f);

    // The model's lids do follow its eyes (ICT-FaceKit's eyeLookDown, from scans of people): about
    // half the gap at 25 degrees down, as the aperture forest reads on the renders (docs/gaze.md).
    EXPECT_GT(lids.share(-25.f), 0.3f);
    EXPECT_LT(lids.share(-25.f), 0.8f);
}

/// The synthetic renderer's face, tracked from its own landmarks' box with the renderer's camera.
class GazeOnRenders : public ::testing::Test {
protected:
    void SetUp() override {
        if (!std::filesystem::exists(test::sourceDir() + "/models/eye_model.ftm") ||
            !std::filesystem::exists(test::sourceDir() + "/models/landmarks_lbf.ftm"))
            GTEST_SKIP() << "models/eye_model.ftm or landmarks_lbf.ftm missing";
        models_ = Models::loadDefault();
        renderer_ = std::make_unique<tools::SyntheticRenderer>(models_.face);
        TrackerConfig config;
        config.camera.focal_length_px = tools::SyntheticFace{}.fx;
        tracker_ = std::make_unique<Tracker>(models_, config);
    }
    tools::SyntheticFace face(float gazeYaw, float gazePitch, float blinkLeft = 0.f, float blinkRight = 0.f) const {
        tools::SyntheticFace f;
        f.rotation = {0.f, 1.f, 0.f, 0.f};               // facing the camera
        f.translation_mm = {0, 0, f.fx * 62.3f / 90.f};  // inter-ocular distance 90 px
        f.gaze_deg = {{{gazeYaw - 1.5f, gazePitch}, {gazeYaw + 1.5f, gazePitch}}};
        const auto& names = models_.face->expressionNames();
        f.expression.assign(names.size(), 0.f);
        const auto set = [&](const char* n, float w) {
            f.expression[static_cast<std::size_t>(std::find(names.begin(), names.end(), n) - names.begin())] = w;
        };
        set("eyeBlink_L", blinkLeft);
        set("eyeBlink_R", blinkRight);
        return f;
    }
    FrameResult track(const tools::SyntheticFace& f, double t) {
        const cv::Mat image = renderer_->render(f);
        FrameResult result;
        tracker_->process(core::viewOf(image), t, {renderer_->faceBox(f)}, result);
        return result;
    }
    static double angleDeg(const Vec3& a, const Vec3& b) {
        return std::acos(std::clamp(static_cast<double>(a.x * b.x + a.y * b.y + a.z * b.z), -1.0, 1.0)) / kDeg;
    }
    Models models_;
    std::unique_ptr<tools::SyntheticRenderer> renderer_;
    std::unique_ptr<Tracker> tracker_;
};

TEST_F(GazeOnRenders, RecoversKnownGaze) {
    double worst = 0.0;
    for (const auto& g : std::vector<std::array<float, 2>>{{0, 0}, {15, 0}, {-15, 5}, {0, -12}}) {
        tracker_->reset();
        const tools::SyntheticFace f = face(g[0], g[1]);
        const FrameResult r = track(f, 0.0);
        ASSERT_EQ(r.faces.size(), 1u);
        ASSERT_TRUE(r.faces[0].gaze);
        for (int e = 0; e < 2; ++e) {
            const EyeGaze& est = e == 0 ? r.faces[0].gaze->left : r.faces[0].gaze->right;
            const double error = angleDeg(est.direction, renderer_->gazeInCamera(f, e));
            worst = std::max(worst, error);
            EXPECT_LT(error, kRenderGazeToleranceDeg) << "gaze " << g[0] << " " << g[1] << ", eye " << e;
            EXPECT_GT(est.openness, 0.7f);
        }
    }
    std::printf("worst angular error on 4 renders: %.2f deg\n", worst);
}

/// The eyeballs are placed from the corner cascade's corners: on renders (other
/// than those it trained on) they must be nearer the true ones than the
/// landmarks' are. Measured over 400 renders: 2.5 -> about 1 % of the
/// inter-ocular distance (eval-gaze).
TEST_F(GazeOnRenders, TheCornerCascadeFindsTheEyeCorners) {
    const EyeModelData& model = model::dataOf(*models_.eyes);
    ASSERT_FALSE(model.corner_stages.empty()) << "the shipped eye model has no corner cascade";
    std::vector<double> landmarkError, refinedError;
    for (const float headYaw : {-20.f, 0.f, 20.f}) {
        for (const auto& g : std::vector<std::array<float, 2>>{{0, 0}, {15, 5}, {-15, -5}}) {
            tools::SyntheticFace f = face(g[0], g[1]);
            const Eigen::Quaternionf q = Eigen::Quaternionf(0.f, 1.f, 0.f, 0.f) *
                                         Eigen::AngleAxisf(headYaw * kDeg, Eigen::Vector3f::UnitY());
            f.rotation = {q.w(), q.x(), q.y(), q.z()};
            tracker_->reset();
            const cv::Mat image = renderer_->render(f);
            FrameResult r;
            tracker_->process(core::viewOf(image), 0.0, {renderer_->faceBox(f)}, r);
            ASSERT_EQ(r.faces.size(), 1u);
            ASSERT_TRUE(r.faces[0].landmarks);
            cv::Mat gray;
            cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
            const Landmarks68 truth = renderer_->landmarks(f);
            const Landmarks68& l = *r.faces[0].landmarks;
            const float iod = renderer_->interocularPx(f);
            for (const Eye eye : {Eye::Left, Eye::Right}) {
                const auto o = static_cast<std::size_t>(outerCorner(eye)), i = static_cast<std::size_t>(innerCorner(eye));
                const auto midpointError = [&](Point2 outer, Point2 inner) {
                    return 100.0 *
                           std::hypot(0.5f * (outer.x + inner.x - truth[o].x - truth[i].x),
                                      0.5f * (outer.y + inner.y - truth[o].y - truth[i].y)) /
                           iod;
                };
                EyePatch patch, scratch;
                ASSERT_TRUE(cutEyePatch(gray, l, eye, patch));
                const auto c = eyeCorners(model, gray, patch, scratch);
                landmarkError.push_back(midpointError(l[o], l[i]));
                refinedError.push_back(midpointError(c[0], c[1]));
            }
        }
    }
    const auto mean = [](const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size()); };
    std::printf("eye-corner midpoint error on 9 renders: landmarks %.2f %%, corner cascade %.2f %% of the inter-ocular distance\n",
                mean(landmarkError), mean(refinedError));
    EXPECT_LT(mean(refinedError), 0.75 * mean(landmarkError));
    EXPECT_LT(mean(refinedError), 2.0);
}

TEST_F(GazeOnRenders, AWinkIsOneEyeAndBothClosedHoldTheGaze) {
    tracker_->reset();
    const FrameResult open = track(face(10, 0), 0.0);
    ASSERT_EQ(open.faces.size(), 1u);
    ASSERT_TRUE(open.faces[0].gaze);
    const FrameResult wink = track(face(10, 0, 1.f, 0.f), 1 / 30.0);
    ASSERT_EQ(wink.faces.size(), 1u);
    const GazeResult& w = *wink.faces[0].gaze;
    EXPECT_LT(w.left.openness, 0.4f);
    EXPECT_GE(w.right.openness, 0.7f);
    const auto& arkit = wink.faces[0].expression->arkit;
    EXPECT_GE(arkit[static_cast<std::size_t>(arkitIndex("eyeBlinkLeft"))], 0.5f);
    EXPECT_LT(arkit[static_cast<std::size_t>(arkitIndex("eyeBlinkRight"))], 0.5f);
    // The open eye does not veer off while the other is closed (beyond the fixation's own noise, ~1.5 degrees).
    EXPECT_LT(angleDeg(w.right.direction_head, open.faces[0].gaze->right.direction_head), 4.0);
    // Both closed: each eye's gaze holds where it was, finite.
    const FrameResult closed = track(face(10, 0, 1.f, 1.f), 2 / 30.0);
    ASSERT_EQ(closed.faces.size(), 1u);
    const GazeResult& c = *closed.faces[0].gaze;
    EXPECT_LT(c.left.openness, 0.4f);
    EXPECT_LT(c.right.openness, 0.4f);
    for (const auto& [now, before] : {std::pair{c.left, w.left}, std::pair{c.right, w.right}}) {
        EXPECT_TRUE(std::isfinite(now.yaw_deg) && std::isfinite(now.pitch_deg));
        EXPECT_LT(angleDeg(now.direction_head, before.direction_head), 0.5) << "the gaze moved while the eyes were closed";
    }
}

/// A user looking down at the keyboard after looking at the screen: the lids
/// lower with the eyes, and that is not a blink (the expected lid gap follows
/// the gaze as the face model's lids do; with 1.2 % per degree it read 0.67).
TEST_F(GazeOnRenders, LookingDownAfterLookingAheadIsNotABlink) {
    tracker_->reset();
    const auto& names = models_.face->expressionNames();
    int frame = 0;
    for (; frame < 40; ++frame) ASSERT_EQ(track(face(0, 0), frame / 30.0).faces.size(), 1u);
    tools::SyntheticFace down = face(0, -25);
    for (const char* n : {"eyeLookDown_L", "eyeLookDown_R"})
        down.expression[static_cast<std::size_t>(std::find(names.begin(), names.end(), n) - names.begin())] = 25.f / kLookDownFullDeg;
    float largestBlink = 0.f, pitch = 0.f;
    for (int i = 0; i < 12; ++i, ++frame) {
        const FrameResult r = track(down, frame / 30.0);
        ASSERT_EQ(r.faces.size(), 1u);
        ASSERT_TRUE(r.faces[0].gaze);
        const auto& arkit = r.faces[0].expression->arkit;
        for (const char* blink : {"eyeBlinkLeft", "eyeBlinkRight"})
            largestBlink = std::max(largestBlink, arkit[static_cast<std::size_t>(arkitIndex(blink))]);
        pitch = r.faces[0].gaze->right.pitch_deg;
    }
    std::printf("looking down 25 deg after 40 frames ahead: largest eyeBlink %.2f, pitch after 12 frames %.1f deg\n", largestBlink, pitch);
    EXPECT_LT(largestBlink, 0.5f);
    EXPECT_LT(pitch, -15.f);
}

TEST_F(GazeOnRenders, AnEyeAtTheFramesBorderGivesFiniteValues) {
    tracker_->reset();
    tools::SyntheticFace f = face(0, 0);
    f.translation_mm.x = -f.translation_mm.z * (f.cx - 15.f) / f.fx;  // the face's right eye at the left edge
    const FrameResult r = track(f, 0.0);
    for (const FaceResult& face : r.faces) EXPECT_EQ(tools::firstNonFinite(face), "");
}

}  // namespace
}  // namespace facetrack
