// The expression stage's lip net (expression/lip_net.hpp): its mouth patch is the one the trainer
// cuts, follows the face wherever it is, however large and rolled, and holds the mouth; a net's
// answer and its mirror image's average as the maths says; the shipped lip net reads a face and
// its mirror image alike (the geometry net's reading of the lips: test_geometry_net.cpp).

#include "expression/lip_net.hpp"
#include "model/internals.hpp"
#include "nn/cnn_model_data.hpp"
#include "test_support.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

namespace facetrack {
namespace {

/// A face's 68 points, jittered by up to a pixel, rolled about the origin: jaw, brows, nose, eyes and
/// a mouth half as wide as the eyes are apart.
core::Shape68 someFace(unsigned seed, float roll = 0.f) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> jitter(-1.f, 1.f);
    const auto pi = static_cast<float>(M_PI);
    core::Shape68 p;
    for (int i = 0; i <= 16; ++i) p.col(i) << 200.f - 70.f * std::cos(pi * i / 16.f), 150.f + 80.f * std::sin(pi * i / 16.f);
    for (int i = 17; i <= 26; ++i) p.col(i) << 145.f + 110.f * static_cast<float>(i - 17) / 9.f, 115.f;
    for (int i = 27; i <= 30; ++i) p.col(i) << 200.f, 130.f + 12.f * static_cast<float>(i - 27);
    for (int i = 31; i <= 35; ++i) p.col(i) << 185.f + 7.5f * static_cast<float>(i - 31), 172.f;
    for (int i = 0; i < 6; ++i) {
        const float t = 2.f * pi * static_cast<float>(i) / 6.f;
        p.col(36 + i) << 170.f - 10.f * std::cos(t), 140.f - 4.f * std::sin(t);
        p.col(42 + i) << 230.f - 10.f * std::cos(t), 140.f - 4.f * std::sin(t);
    }
    for (int k = 48; k < 68; ++k) {
        const float t = 2.f * pi * static_cast<float>(k - 48) / 20.f;
        p.col(k) << 200.f - 25.f * std::cos(t), 195.f - 8.f * std::sin(t);
    }
    for (float& v : p.reshaped()) v += jitter(rng);
    Eigen::Matrix2f r;
    r << std::cos(roll), -std::sin(roll), std::sin(roll), std::cos(roll);
    return r * p;
}

Eigen::Vector2f mapped(const cv::Matx23d& m, float u, float v) {
    return {static_cast<float>(m(0, 0) * u + m(0, 1) * v + m(0, 2)), static_cast<float>(m(1, 0) * u + m(1, 1) * v + m(1, 2))};
}

TEST(MouthPatch, IsTheOneTheTrainerCuts) {
    std::ifstream in(test::sourceDir() + "/tests/data/mouth_patch_fixture.txt");
    core::Shape68 face;
    for (int i = 0; i < core::kLandmarks; ++i) in >> face(0, i) >> face(1, i);
    cv::Matx23d expected;
    for (int k = 0; k < 6; ++k) in >> expected.val[k];
    ASSERT_TRUE(in) << "tests/data/mouth_patch_fixture.txt (tools/train/make_parity_fixture.py)";
    const cv::Matx23d m = expression::mouthPatch(face, 64, 0.75f).to_frame;
    for (int k = 0; k < 6; ++k) EXPECT_NEAR(m.val[k], expected.val[k], 1e-3 * std::max(1.0, std::abs(expected.val[k]))) << k;
}

TEST(MouthPatch, FollowsTheFaceAndHoldsTheMouth) {
    const core::Shape68 face = someFace(1);
    const cv::Matx23d m = expression::mouthPatch(face, 64, 0.75f).to_frame;
    for (const float angle : {0.3f, -0.7f, 2.5f}) {
        Eigen::Matrix2f r;
        r << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
        const Eigen::Vector2f shift(-40.f, 90.f);
        const core::Shape68 moved = ((2.5f * r * face).colwise() + shift).eval();
        const cv::Matx23d n = expression::mouthPatch(moved, 64, 0.75f).to_frame;
        for (const auto& [u, v] : {std::pair{0.f, 0.f}, {63.f, 0.f}, {31.5f, 40.f}})
            EXPECT_LT((mapped(n, u, v) - (2.5f * r * mapped(m, u, v) + shift)).norm(), 1e-3f) << angle;
    }
    // every mouth point inside the patch
    const cv::Matx23d inverse = [&] {
        cv::Matx23d i;
        cv::invertAffineTransform(m, i);
        return i;
    }();
    for (int k = 48; k < 68; ++k) {
        const Eigen::Vector2f u = mapped(inverse, face(0, k), face(1, k));
        EXPECT_TRUE(u.x() > 0.f && u.x() < 63.f && u.y() > 0.f && u.y() < 63.f) << k << ": " << u.transpose();
    }
}

TEST(LipPoints, OfTheMirrorImageMirrorBack) {
    std::mt19937 rng(2);
    std::normal_distribution<float> normal;
    expression::LipPoints lips;
    for (float& v : lips.reshaped()) v = normal(rng);
    EXPECT_LT((expression::mirroredLips(expression::mirroredLips(lips)) - lips).cwiseAbs().maxCoeff(), 1e-7f);
    // the corners swap: the outer line's first point (a corner) with its eleventh
    EXPECT_FLOAT_EQ(expression::mirroredLips(lips)(0, 0), -lips(0, 10));
    EXPECT_FLOAT_EQ(expression::mirroredLips(lips)(1, 20), lips(1, 30));
}

TEST(LipNet, AveragesItsAnswerWithTheMirrorImagesAboutTheMouthsAnchor) {
    // the fixture net answers (+0.25, +0.5) for every point of any patch: mirrored back, x averages to 0
    expression::LipNet net(test::fixtureBytes("lip_fixture.onnx"), 64, 0.75f, "lip_fixture.onnx");
    const core::Shape68 face = someFace(3, 0.3f);
    cv::Mat gray(480, 640, CV_8UC1);
    cv::randu(gray, 0, 255);
    const expression::LipPoints& lips = net.predict(gray, face);
    // the anchor: the mouth points' mean height in the normalised frame
    const expression::NormalisingFrame frame = expression::normalisingFrame(face);
    const float anchor = (frame.unroll() * (face.middleCols<20>(48).colwise() - frame.centre) / frame.rms).row(1).mean();
    for (int k = 0; k < nn::kLipPoints; ++k) {
        EXPECT_NEAR(lips(0, k), 0.f, 1e-4f) << k;
        EXPECT_NEAR(lips(1, k), anchor + 0.75f * 0.5f, 1e-4f) << k;
    }
}

TEST(ShippedCnn, ReadsTheLipsOfAFaceAndItsMirrorImageAlike) {
    const std::string path = test::sourceDir() + "/models/cnn_cascade.ftm";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "models/cnn_cascade.ftm is not shipped";
    const auto cascade = CnnModel::load(path);
    const nn::CnnModelData& d = model::dataOf(*cascade);
    ASSERT_FALSE(d.lip_net.empty()) << "the shipped file has no lip net";
    expression::LipNet net(d.lip_net, d.lip_patch_size, d.lip_patch_half, path);
    cv::Mat gray(480, 640, CV_8UC1);
    cv::RNG(7).fill(gray, cv::RNG::UNIFORM, 0, 256);
    cv::GaussianBlur(gray, gray, cv::Size(0, 0), 3.0);
    cv::Mat flipped;
    cv::flip(gray, flipped, 1);
    const core::Shape68 face = someFace(8, 0.1f);
    core::Shape68 mirror;
    for (int i = 0; i < core::kLandmarks; ++i) {
        const int from = core::kMirror68[static_cast<std::size_t>(i)];
        mirror.col(i) << 639.f - face(0, from), face(1, from);
    }
    const expression::LipPoints lips = net.predict(gray, face);
    ASSERT_TRUE(lips.allFinite());
    const float difference = (net.predict(flipped, mirror) - expression::mirroredLips(lips)).cwiseAbs().maxCoeff();
    EXPECT_LT(difference, 0.01f);
    std::printf("lips of the mirror image against the face's mirrored: %.5f\n", difference);
}

}  // namespace
}  // namespace facetrack
