#include "core/pts.hpp"
#include "core/shape2d.hpp"
#include "facetrack/error.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace facetrack::core {
namespace {

Shape2 randomShape(int n, unsigned seed) {
    std::srand(seed);
    return Shape2::Random(2, n) * 50.f;
}

TEST(Pts, WrittenPointsReadBackAndABadFileIsAClearError) {
    const Shape2 points = randomShape(68, 3) + Shape2::Constant(2, 68, 60.f);
    const std::string path = test::tempPath("round_trip.pts");
    writePts(path, points);
    EXPECT_LT((readPts(path) - points).cwiseAbs().maxCoeff(), 1e-3f);
    EXPECT_THROW(writePts("/nonexistent/dir/x.pts", points), Error);
    EXPECT_THROW(readPts("/nonexistent/dir/x.pts"), Error);
}

TEST(Shape2d, AlignSimilarityRecoversAKnownTransform) {
    const Shape2 from = randomShape(68, 1);
    Similarity truth;
    truth.scale = 1.7f;
    truth.angle = 0.4f;
    truth.translation = {12.f, -5.f};
    const Similarity fit = alignSimilarity(from, truth.apply(from));
    EXPECT_NEAR(fit.scale, 1.7f, 1e-4f);
    EXPECT_NEAR(fit.angle, 0.4f, 1e-4f);
    EXPECT_NEAR((fit.translation - truth.translation).norm(), 0.f, 1e-3f);
    EXPECT_NEAR((fit.inverse().apply(truth.apply(from)) - from).cwiseAbs().maxCoeff(), 0.f, 1e-3f);
}

TEST(Shape2d, ProcrustesMeanOfTransformedCopiesIsTheShape) {
    const Shape2 base = randomShape(68, 2);
    std::vector<Shape2> shapes;
    for (int k = 0; k < 5; ++k) {
        Similarity t;
        t.scale = 0.5f + 0.3f * k;
        t.angle = 0.2f * k - 0.4f;
        t.translation = {10.f * k, -3.f * k};
        shapes.push_back(t.apply(base));
    }
    const Shape2 mean = procrustesMean(shapes);
    const Shape2 aligned = alignSimilarity(base, mean).apply(base);
    EXPECT_LT((aligned - mean).cwiseAbs().maxCoeff(), 1e-4f);
    EXPECT_NEAR(std::sqrt(mean.squaredNorm() / 68.f), 1.f, 1e-4f);
}

TEST(Shape2d, NmeIsMeanErrorOverOuterEyeCornerDistance) {
    Shape2 truth = Shape2::Zero(2, 68);
    truth.col(36) = Eigen::Vector2f(0.f, 0.f);
    truth.col(45) = Eigen::Vector2f(100.f, 0.f);
    Shape2 predicted = truth;
    predicted.row(0).array() += 3.f;  // every point 3 px off
    EXPECT_NEAR(nme68(predicted, truth), 0.03f, 1e-6f);
    predicted.col(30).y() += 4.f;  // the nose tip 5 px off
    const Eigen::VectorXf errors = pointErrors68(predicted, truth);
    EXPECT_NEAR(errors(30), 0.05f, 1e-6f);
    EXPECT_NEAR(errors(0), 0.03f, 1e-6f);
    EXPECT_NEAR(nme68(predicted, truth), (67 * 0.03f + 0.05f) / 68, 1e-6f);
}

TEST(Shape2d, BoxNmeIsMeanErrorOverTheTruthsBoxSize) {
    Shape2 truth = Shape2::Zero(2, 68);
    truth.col(0) = Eigen::Vector2f(10.f, 20.f);
    truth.col(1) = Eigen::Vector2f(110.f, 20.f);
    truth.col(2) = Eigen::Vector2f(60.f, 420.f);  // box 100 x 400: sqrt(w h) = 200
    for (int i = 3; i < 68; ++i) truth.col(i) = Eigen::Vector2f(60.f, 100.f);
    Shape2 predicted = truth;
    predicted.row(1).array() += 4.f;
    EXPECT_NEAR(nmeBox(predicted, truth), 0.02f, 1e-6f);
    EXPECT_THROW(nmeBox(predicted, Shape2::Zero(2, 68)), Error);  // an empty box
    EXPECT_THROW(nmeBox(predicted.leftCols(5), truth), Error);
}

}  // namespace
}  // namespace facetrack::core
