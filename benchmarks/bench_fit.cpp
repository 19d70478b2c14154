// The fit stage on one core: a warm (tracking) fit per frame, a cold fit, and
// the identity calibration over 30 frames, on synthetic landmarks of the
// shipped face model (a head turning slowly, 1.5 px noise).

#include "bench_support.hpp"

#include "facetrack/face_model.hpp"
#include "fit/face_fitter.hpp"
#include "model/internals.hpp"

#include <random>

namespace facetrack::bench {
namespace {

struct SyntheticClip {
    std::shared_ptr<const fit::FitBasis> basis;
    core::Camera camera = core::cameraFor(640, 480, 60.0, 0.0);
    std::vector<fit::Landmarks2d> frames;
};

/// 120 frames: yaw sweeping +-30 deg, the jaw opening and closing, at 60 cm.
SyntheticClip syntheticClip() {
    SyntheticClip clip;
    const auto model = FaceModel::loadDefault();
    clip.basis = std::make_shared<const fit::FitBasis>(fit::buildFitBasis(model::dataOf(*model)));
    std::mt19937 rng(1);
    std::normal_distribution<double> noise(0.0, 1.5);
    for (int t = 0; t < 120; ++t) {
        fit::FaceParams p;
        const double phase = 2.0 * 3.14159265358979 * t / 120.0;
        p.pose << fit::omegaFromEuler({5.0 * std::sin(2 * phase), 30.0 * std::sin(phase), 0.0}), 0.0, 0.0, 60.0;
        p.expression = Eigen::VectorXd::Zero(clip.basis->expressionCount());
        p.expression[0] = 0.5 + 0.5 * std::sin(3 * phase);
        const auto contour = fit::silhouetteContour(*clip.basis, clip.basis->neutral, clip.camera, p);
        fit::Landmarks2d l = fit::projectLandmarks(*clip.basis, clip.basis->neutral, clip.camera, p, contour);
        for (int i = 0; i < l.cols(); ++i) l.col(i) += Eigen::Vector2d(noise(rng), noise(rng));
        clip.frames.push_back(l);
    }
    return clip;
}

void BM_Fit_Warm(benchmark::State& state) {
    const SyntheticClip clip = syntheticClip();
    fit::FaceFitter fitter(clip.basis, {});
    fit::FaceParams params;
    fitter.fit(clip.camera, clip.frames[0], params, false);
    std::size_t t = 0;
    double iterations = 0;
    for (auto _ : state) {
        t = (t + 1) % clip.frames.size();
        iterations += fitter.fit(clip.camera, clip.frames[t], params, true).iterations;
    }
    state.counters["iterations"] = benchmark::Counter(iterations, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_Fit_Warm)->Unit(benchmark::kMicrosecond)->MinTime(minTime(2.0));

void BM_Fit_Cold(benchmark::State& state) {
    const SyntheticClip clip = syntheticClip();
    fit::FaceFitter fitter(clip.basis, {});
    std::size_t t = 0;
    for (auto _ : state) {
        t = (t + 1) % clip.frames.size();
        fit::FaceParams params;
        benchmark::DoNotOptimize(fitter.fit(clip.camera, clip.frames[t], params, false));
    }
}
BENCHMARK(BM_Fit_Cold)->Unit(benchmark::kMicrosecond)->MinTime(minTime(2.0));

void BM_Fit_IdentityCalibration30Frames(benchmark::State& state) {
    const SyntheticClip clip = syntheticClip();
    fit::FaceFitter fitter(clip.basis, {});
    std::vector<fit::CalibrationFrame> window;
    for (int t = 0; t < 120; t += 4) {
        fit::CalibrationFrame c{clip.camera, clip.frames[t], {}, {}};
        c.contour = fitter.fit(clip.camera, clip.frames[t], c.params, false).contour;
        window.push_back(c);
    }
    for (auto _ : state) {
        auto copy = window;
        benchmark::DoNotOptimize(fit::calibrateIdentity(*clip.basis, copy, fitter.settings()));
    }
}
BENCHMARK(BM_Fit_IdentityCalibration30Frames)->Unit(benchmark::kMillisecond)->MinTime(minTime(2.0));

}  // namespace
}  // namespace facetrack::bench
