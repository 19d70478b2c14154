#include "core/one_euro.hpp"
#include "filter/filter_stage.hpp"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <cmath>
#include <random>

namespace facetrack {
namespace {

TEST(OneEuroFilter, PassesAConstantAndTheFirstSample) {
    core::OneEuroFilter f;
    const Eigen::VectorXd x = Eigen::VectorXd::Constant(3, 2.5);
    EXPECT_EQ(f(x, 1.0 / 30), x);
    for (int i = 0; i < 10; ++i) EXPECT_LT((f(x, 1.0 / 30) - x).norm(), 1e-12);
}

TEST(OneEuroFilter, SmoothsNoiseAtRestAndFollowsFastMotionWithLittleLag) {
    std::mt19937 rng(4);
    std::normal_distribution<double> noise(0.0, 1.0);
    core::OneEuroFilter still({1.0, 1.0, 1.0});
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
        core::OneEuroFilter f({1.0, beta, 1.0});
        double y = 0;
        for (int i = 0; i < 60; ++i) y = f(Eigen::VectorXd::Constant(1, 100.0 * i / 30), 1.0 / 30, 10.0)[0];
        return 100.0 * 59 / 30 - y;
    };
    EXPECT_LT(lagAfter(5.0), 0.5 * lagAfter(0.0));
}

TEST(OneEuroFilter, APerElementCutoffScaleHoldsSomeElementsSteadierThanOthers) {
    std::mt19937 rng(8);
    std::normal_distribution<double> noise(0.0, 1.0);
    core::OneEuroFilter f({1.0, 0.0, 1.0});
    f.setMinCutoffScale(Eigen::Vector3d(0.5, 1.0, 2.0));
    Eigen::Vector3d outSq = Eigen::Vector3d::Zero();
    for (int i = 0; i < 600; ++i) {
        const Eigen::VectorXd y = f(Eigen::Vector3d::Constant(noise(rng)), 1.0 / 30);  // the same noise in all three
        if (i > 30) outSq += y.cwiseAbs2();
    }
    EXPECT_LT(outSq[0], 0.8 * outSq[1]);  // a lower cutoff lets less noise through
    EXPECT_LT(outSq[1], 0.8 * outSq[2]);
    // A scale of another size than the samples' is ignored: every element as set.
    core::OneEuroFilter plain({1.0, 0.0, 1.0}), mismatched({1.0, 0.0, 1.0});
    mismatched.setMinCutoffScale(Eigen::Vector2d(0.5, 0.5));
    for (int i = 0; i < 20; ++i) {
        const Eigen::VectorXd x = Eigen::Vector3d::Constant(noise(rng));
        EXPECT_EQ(plain(x, 1.0 / 30), mismatched(x, 1.0 / 30));
    }
}

TEST(OneEuroFilter, RestartsOnResetOrBadTime) {
    core::OneEuroFilter f;
    f(Eigen::VectorXd::Zero(2), 0.1);
    const Eigen::VectorXd x = Eigen::VectorXd::Constant(2, 7.0);
    f.reset();
    EXPECT_EQ(f(x, 0.1), x);
    EXPECT_EQ(f(Eigen::VectorXd::Constant(2, 1.0), 0.0), Eigen::VectorXd::Constant(2, 1.0));  // dt <= 0: no history
    EXPECT_TRUE(f(Eigen::VectorXd::Constant(2, 3.0), 0.1).allFinite());
}

TEST(MotionSpeed, IsTheSmoothedSpeedOfAPoint) {
    core::MotionSpeed speed(1.0);
    EXPECT_EQ(speed({5.0, 5.0}, 0.1), 0.0);  // the first position has no speed
    double v = 0.0;
    for (int i = 1; i <= 100; ++i) v = speed({5.0 + 3.0 * i / 30, 5.0 - 4.0 * i / 30}, 1.0 / 30, 2.0);
    EXPECT_NEAR(v, 2.5, 1e-3);                // 5 units per second over a scale of 2
    EXPECT_EQ(speed({0.0, 0.0}, -1.0), 0.0);  // a bad time step starts again
    speed.reset();
    EXPECT_EQ(speed({1.0, 1.0}, 0.1), 0.0);
}

/// A face of 68 points, 60 px between the outer eye corners (points 36, 45).
Eigen::VectorXd facePoints() {
    Eigen::VectorXd p(136);
    for (int i = 0; i < 68; ++i) p.segment<2>(2 * i) << 100.0 + 60.0 * (i % 9) / 8.0, 80.0 + 5.0 * (i / 9);
    p.segment<2>(2 * 36) << 100.0, 100.0;
    p.segment<2>(2 * 45) << 160.0, 100.0;
    return p;
}

/// 120 frames at 30 fps of facePoints() with 0.5 px of independent noise, the
/// whole face moving right at `speedPxPerS` from frame 30 on, through the
/// filter stage (`wholeStage`) or a OneEuroFilter on the points alone (each
/// point's own speed, the same settings). Over the frames after the first 30:
/// the mean distance of the output's centroid from the true one (lag) and the
/// RMS second difference of the output points (jitter).
struct FilterRun {
    double lag = 0.0, jitter = 0.0;
};
FilterRun filterPoints(bool wholeStage, double speedPxPerS) {
    const core::OneEuroSettings config{1.0, 2.0, 1.0};  // TrackerConfig::filter's defaults
    const auto stage = filter::makeFilterStage(nullptr, config, true);
    const auto state = stage->newFaceState();
    core::OneEuroFilter alone({config.min_cutoff_hz, config.beta, config.derivative_cutoff_hz});
    pipeline::FaceTrack face;
    const cv::Mat gray(8, 8, CV_8UC1, cv::Scalar(0));
    const double dt = 1.0 / 30;
    const pipeline::FrameInput frame{{}, gray, {}, dt};
    std::mt19937 rng(11);
    std::normal_distribution<double> noise(0.0, 0.5);
    const Eigen::VectorXd still = facePoints();
    const double stillCentroidX = still(Eigen::seq(0, 134, 2)).mean();
    constexpr int kFrames = 120, kStart = 30;
    std::vector<Eigen::VectorXd> out;
    FilterRun run;
    for (int t = 0; t < kFrames; ++t) {
        const double shift = std::max(0, t - kStart) * speedPxPerS * dt;
        Eigen::VectorXd sample = still;
        for (int i = 0; i < 68; ++i) sample.segment<2>(2 * i) += Eigen::Vector2d(shift + noise(rng), noise(rng));
        if (wholeStage) {
            face.result.landmarks.emplace();
            for (std::size_t i = 0; i < 68; ++i)
                (*face.result.landmarks)[i] = {static_cast<float>(sample[2 * i]), static_cast<float>(sample[2 * i + 1])};
            face.fresh = t == 0;
            EXPECT_EQ(stage->run(frame, face, state.get()), pipeline::Outcome::Ok);
            for (std::size_t i = 0; i < 68; ++i) sample.segment<2>(2 * i) << (*face.result.landmarks)[i].x, (*face.result.landmarks)[i].y;
        } else {
            sample = alone(sample, dt, 60.0);
        }
        out.push_back(sample);
        if (t <= kStart) continue;
        run.lag += std::abs(sample(Eigen::seq(0, 134, 2)).mean() - (stillCentroidX + shift)) / (kFrames - kStart - 1);
        run.jitter += (out[t] - 2.0 * out[t - 1] + out[t - 2]).squaredNorm() / 68.0 / (kFrames - kStart - 1);
    }
    run.jitter = std::sqrt(run.jitter);
    return run;
}

TEST(FilterStage, TheFacesMotionCutsTheLagOfAMovingFaceAndLittleOfTheSmoothingOfAStillOne) {
    const FilterRun stillStage = filterPoints(true, 0.0), stillAlone = filterPoints(false, 0.0);
    const FilterRun movingStage = filterPoints(true, 120.0), movingAlone = filterPoints(false, 120.0);
    std::printf("still: jitter %.3f px (points alone %.3f); moving 2 eye distances/s: lag %.2f px (points alone %.2f)\n", stillStage.jitter,
                stillAlone.jitter, movingStage.lag, movingAlone.lag);
    EXPECT_LT(stillStage.jitter, 1.15 * stillAlone.jitter);
    EXPECT_LT(movingStage.lag, 0.6 * movingAlone.lag);
}

}  // namespace
}  // namespace facetrack
