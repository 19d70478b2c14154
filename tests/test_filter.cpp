#include "filter/one_euro.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace facetrack {
namespace {

TEST(OneEuroFilter, PassesAConstantAndTheFirstSample) {
    filter::OneEuroFilter f;
    const Eigen::VectorXd x = Eigen::VectorXd::Constant(3, 2.5);
    EXPECT_EQ(f(x, 1.0 / 30), x);
    for (int i = 0; i < 10; ++i) EXPECT_LT((f(x, 1.0 / 30) - x).norm(), 1e-12);
}

TEST(OneEuroFilter, SmoothsNoiseAtRestAndFollowsFastMotionWithLittleLag) {
    std::mt19937 rng(4);
    std::normal_distribution<double> noise(0.0, 1.0);
    filter::OneEuroFilter still({1.0, 1.0, 1.0});
    double rawSq = 0, outSq = 0;
    for (int i = 0; i < 300; ++i) {
        const double n = noise(rng);
        const double y = still(Eigen::VectorXd::Constant(1, n), 1.0 / 30, 10.0)[0];
        if (i > 30) {
            rawSq += n * n;
            outSq += y * y;
        }
    }
    EXPECT_LT(outSq, 0.25 * rawSq);

    // A ramp of 100 units per second: a high beta keeps the lag small.
    auto lagAfter = [](double beta) {
        filter::OneEuroFilter f({1.0, beta, 1.0});
        double y = 0;
        for (int i = 0; i < 60; ++i) y = f(Eigen::VectorXd::Constant(1, 100.0 * i / 30), 1.0 / 30, 10.0)[0];
        return 100.0 * 59 / 30 - y;
    };
    EXPECT_LT(lagAfter(5.0), 0.5 * lagAfter(0.0));
}

TEST(OneEuroFilter, RestartsOnResetOrBadTime) {
    filter::OneEuroFilter f;
    f(Eigen::VectorXd::Zero(2), 0.1);
    const Eigen::VectorXd x = Eigen::VectorXd::Constant(2, 7.0);
    f.reset();
    EXPECT_EQ(f(x, 0.1), x);
    EXPECT_EQ(f(Eigen::VectorXd::Constant(2, 1.0), 0.0), Eigen::VectorXd::Constant(2, 1.0));  // dt <= 0: no history
    EXPECT_TRUE(f(Eigen::VectorXd::Constant(2, 3.0), 0.1).allFinite());
}

}  // namespace
}  // namespace facetrack
