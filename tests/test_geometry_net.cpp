// The expression stage's geometry net (expression/geometry_net.hpp): its features do not change
// when the face moves, scales or rolls in the image; the mirror image's features and readings are
// the face's with left and right swapped, the lips' too; the file stores it and the lip net, refuses
// a damaged one; the shipped file reads the shapes pack_cnn chose from it.

#include "expression/geometry_net.hpp"
#include "expression/lip_net.hpp"
#include "facetrack/error.hpp"
#include "facetrack/tracker.hpp"
#include "model/internals.hpp"
#include "nn/cnn_model_data.hpp"
#include "test_support.hpp"

#include <cmath>
#include <filesystem>
#include <random>

namespace facetrack {
namespace {

core::Shape68 someFace(unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> jitter(-4.f, 4.f);
    core::Shape68 p;
    for (int i = 0; i < core::kLandmarks; ++i)
        p.col(i) << 200.f + 3.f * static_cast<float>(i % 17) + jitter(rng), 150.f + 2.f * static_cast<float>(i / 17) + jitter(rng);
    // the eyes level and apart, as on a face: the features' roll is the eye line's
    for (int i = 36; i < 42; ++i) p.col(i) << 170.f + jitter(rng), 140.f + jitter(rng);
    for (int i = 42; i < 48; ++i) p.col(i) << 230.f + jitter(rng), 140.f + jitter(rng);
    return p;
}

core::Shape68 mirrorImage(const core::Shape68& p) {
    core::Shape68 m;
    for (int i = 0; i < core::kLandmarks; ++i) {
        const int from = core::kMirror68[static_cast<std::size_t>(i)];
        m.col(i) << 640.f - p(0, from), p(1, from);
    }
    return m;
}

std::vector<nn::DenseLayer> someLayers(const std::vector<int>& sizes, unsigned seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> normal(0.f, 0.3f);
    std::vector<nn::DenseLayer> layers;
    for (std::size_t i = 1; i < sizes.size(); ++i) {
        nn::DenseLayer l;
        l.rows = sizes[i];
        l.cols = sizes[i - 1];
        for (int k = 0; k < l.rows * l.cols; ++k) l.weight.push_back(normal(rng));
        for (int k = 0; k < l.rows; ++k) l.bias.push_back(normal(rng));
        layers.push_back(std::move(l));
    }
    return layers;
}

TEST(GeometryFeatures, AreTheSameWhereverTheFaceIsAndHoweverLargeAndRolled) {
    const core::Shape68 face = someFace(1);
    const expression::GeometryFeatures f = expression::geometryFeatures(face, 10.0, -20.0);
    for (const float angle : {0.3f, -0.7f, 2.5f}) {
        Eigen::Matrix2f r;
        r << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
        const core::Shape68 moved = ((2.5f * r * face).colwise() + Eigen::Vector2f(-40.f, 90.f)).eval();
        EXPECT_LT((expression::geometryFeatures(moved, 10.0, -20.0) - f).cwiseAbs().maxCoeff(), 1e-4f) << angle;
    }
    // unit root-mean-square size, and the pose's sines last
    EXPECT_NEAR(f.head<2 * core::kLandmarks>().squaredNorm() / core::kLandmarks, 1.f, 1e-4f);
    EXPECT_NEAR(f[2 * core::kLandmarks], std::sin(10.0 * M_PI / 180.0), 1e-6);
    EXPECT_NEAR(f[2 * core::kLandmarks + 1], std::sin(-20.0 * M_PI / 180.0), 1e-6);
    // a brow raised is a change of the features
    core::Shape68 raised = face;
    raised.middleCols<10>(17).row(1).array() -= 5.f;
    EXPECT_GT((expression::geometryFeatures(raised, 10.0, -20.0) - f).norm(), 0.05f);
}

TEST(GeometryFeatures, OfTheMirrorImageAreTheFacesMirrored) {
    const core::Shape68 face = someFace(2);
    const expression::GeometryFeatures direct = expression::geometryFeatures(face, 5.0, 15.0);
    EXPECT_LT((expression::mirroredGeometryFeatures(mirrorImage(face), 5.0, -15.0) - direct).cwiseAbs().maxCoeff(), 1e-4f);
}

TEST(GeometryNet, ReadsAFaceAndItsMirrorImageAlikeWithLeftAndRightSwapped) {
    const std::vector<std::string> names = {"browDown_L", "jawOpen", "browDown_R"};
    expression::GeometryNet net(someLayers({nn::kGeometryFeatures, 16, 3}, 3), names);
    const core::Shape68 face = someFace(3);
    const Eigen::VectorXf w = net.predict(face, 0.0, 12.0);
    const Eigen::VectorXf m = net.predict(mirrorImage(face), 0.0, -12.0);
    EXPECT_TRUE((w.array() >= 0.f).all() && (w.array() <= 1.f).all());
    EXPECT_NEAR(m[0], w[2], 1e-5f);
    EXPECT_NEAR(m[2], w[0], 1e-5f);
    EXPECT_NEAR(m[1], w[1], 1e-5f);
    // one pass is the layers' maths: ReLU between, a sigmoid after the last
    const auto layers = someLayers({nn::kGeometryFeatures, 4, 2}, 4);
    expression::GeometryNet small(layers, {"jawOpen", "mouthClose"});
    const expression::GeometryFeatures f = expression::geometryFeatures(face, 0.0, 0.0);
    const Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> w1(layers[0].weight.data(), 4,
                                                                                                     nn::kGeometryFeatures);
    const Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> w2(layers[1].weight.data(), 2, 4);
    const Eigen::VectorXf hidden = (w1 * f + Eigen::Map<const Eigen::VectorXf>(layers[0].bias.data(), 4)).cwiseMax(0.f);
    const Eigen::VectorXf logits = w2 * hidden + Eigen::Map<const Eigen::VectorXf>(layers[1].bias.data(), 2);
    const Eigen::VectorXf out = small.forward(f);
    for (int k = 0; k < 2; ++k) EXPECT_NEAR(out[k], 1.f / (1.f + std::exp(-logits[k])), 1e-5f);
    EXPECT_THROW(expression::GeometryNet(someLayers({nn::kGeometryFeatures, 2}, 5), {"browDown_L", "jawOpen"}), Error);  // no partner
}

TEST(CnnModelFile, HoldsAGeometryNetBesideTheCascadeAndRefusesABadOne) {
    nn::CnnModelData m;
    m.expressions = {"jawOpen"};
    m.stages.push_back({1, test::fixtureBytes("cnn_parity.onnx")});
    m.expressions_only = true;
    m.geometry_net = someLayers({nn::kGeometryFeatures, 8, 1}, 6);
    m.geometry_reported = {true};
    m.geometry_neutral = {0.1f};
    m.geometry_full = {0.9f};
    const std::string path = test::tempPath("cascade_geometry.ftm");
    nn::writeCnnModel(path, m);
    const auto loaded = CnnModel::load(path);
    const nn::CnnModelData& back = model::dataOf(*loaded);
    ASSERT_EQ(back.geometry_net.size(), 2u);
    EXPECT_EQ(back.geometry_net[1].weight, m.geometry_net[1].weight);
    EXPECT_EQ(back.geometry_net[0].bias, m.geometry_net[0].bias);
    EXPECT_EQ(back.geometry_reported, m.geometry_reported);
    EXPECT_EQ(back.geometry_neutral, m.geometry_neutral);
    EXPECT_EQ(back.geometry_full, m.geometry_full);
    nn::CnnModelData bad = m;
    bad.geometry_net[0].cols = 10;  // not the features' count
    EXPECT_THROW(nn::writeCnnModel(test::tempPath("bad.ftm"), bad), Error);
    bad = m;
    bad.geometry_net[1].weight[0] = std::nanf("");
    EXPECT_THROW(nn::writeCnnModel(test::tempPath("bad.ftm"), bad), Error);
    bad = m;
    bad.geometry_full = {0.1f};  // full at the neutral
    EXPECT_THROW(nn::writeCnnModel(test::tempPath("bad.ftm"), bad), Error);
    bad = m;
    bad.geometry_net.clear();  // readings without the net
    EXPECT_THROW(nn::writeCnnModel(test::tempPath("bad.ftm"), bad), Error);
}

TEST(GeometryNet, ReadsTheLipsAndAFaceAndItsMirrorImageAlike) {
    const std::vector<std::string> names = {"mouthPress_L", "mouthPucker", "mouthPress_R"};
    expression::GeometryNet net(someLayers({nn::kGeometryFeatures + 2 * nn::kLipPoints, 16, 3}, 3), names);
    ASSERT_TRUE(net.readsLips());
    const core::Shape68 face = someFace(4);
    const core::Shape68 mirror = mirrorImage(face);
    std::mt19937 rng(5);
    std::normal_distribution<float> normal(0.f, 0.3f);
    expression::LipPoints lips;
    for (float& v : lips.reshaped()) v = normal(rng);
    const Eigen::VectorXf w = net.predict(face, 0.0, 12.0, &lips);
    const expression::LipPoints mirroredLips = expression::mirroredLips(lips);
    const Eigen::VectorXf m = net.predict(mirror, 0.0, -12.0, &mirroredLips);
    EXPECT_NEAR(m[0], w[2], 1e-5f);
    EXPECT_NEAR(m[1], w[1], 1e-5f);
    // the lips count
    expression::LipPoints pursed = lips;
    pursed.row(0) *= 0.7f;
    EXPECT_GT((net.predict(face, 0.0, 12.0, &pursed) - w).cwiseAbs().maxCoeff(), 1e-3f);
    EXPECT_THROW(net.predict(face, 0.0, 12.0), Error);  // a net that reads the lips needs them
    EXPECT_THROW(expression::GeometryNet(someLayers({nn::kGeometryFeatures + 3, 2}, 6), {"jawOpen", "mouthClose"}), Error);
}

TEST(CnnModelFile, HoldsALipNetBesideTheGeometryNetAndRefusesABadOne) {
    nn::CnnModelData m;
    m.expressions = {"jawOpen"};
    m.stages.push_back({1, test::fixtureBytes("cnn_parity.onnx")});
    m.expressions_only = true;
    m.geometry_net = someLayers({nn::kGeometryFeatures + 2 * nn::kLipPoints, 8, 1}, 7);
    m.geometry_reported = {true};
    m.geometry_neutral = {0.1f};
    m.geometry_full = {0.9f};
    m.lip_net = test::fixtureBytes("lip_fixture.onnx");
    m.lip_patch_size = 64;
    m.lip_patch_half = 0.75f;
    const std::string path = test::tempPath("cascade_lips.ftm");
    nn::writeCnnModel(path, m);
    const nn::CnnModelData back = nn::readCnnModel(path);
    EXPECT_EQ(back.lip_net, m.lip_net);
    EXPECT_EQ(back.lip_patch_size, 64);
    EXPECT_EQ(back.lip_patch_half, 0.75f);
    nn::CnnModelData bad = m;
    bad.lip_net.clear();  // a geometry net reading lips nobody reads
    EXPECT_THROW(nn::writeCnnModel(test::tempPath("bad.ftm"), bad), Error);
    bad = m;
    bad.lip_patch_half = 0.f;
    EXPECT_THROW(nn::writeCnnModel(test::tempPath("bad.ftm"), bad), Error);
    bad = m;
    bad.geometry_net.clear();
    bad.geometry_reported.clear();
    bad.geometry_neutral.clear();
    bad.geometry_full.clear();  // a lip net without the geometry net
    EXPECT_THROW(nn::writeCnnModel(test::tempPath("bad.ftm"), bad), Error);
}

TEST(ShippedCnn, ReadsTheBrowsFromTheLandmarksGeometry) {
    const std::string path = test::sourceDir() + "/models/cnn_cascade.ftm";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "models/cnn_cascade.ftm is not shipped";
    Models models = Models::loadDefault();
    models.cnn = CnnModel::load(path);
    const nn::CnnModelData& d = model::dataOf(*models.cnn);
    ASSERT_FALSE(d.geometry_net.empty());
    for (const char* name : {"browInnerUp_L", "browInnerUp_R", "browDown_L", "browDown_R"}) {
        const auto it = std::find(d.expressions.begin(), d.expressions.end(), name);
        ASSERT_NE(it, d.expressions.end()) << name;
        EXPECT_TRUE(d.geometry_reported[static_cast<std::size_t>(it - d.expressions.begin())]) << name;
    }
    const Tracker tracker(models);
    const auto estimated = tracker.estimatedShapes();
    EXPECT_NE(std::find(estimated.begin(), estimated.end(), "browInnerUp"), estimated.end());
}

}  // namespace
}  // namespace facetrack
