#pragma once
// Training an LbfModel (Ren et al. 2014), stage by stage. Not part of the
// runtime library: tools/train/landmarks and the tests link it.

#include "landmarks/lbf_model.hpp"

#include <opencv2/core.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace facetrack::landmarks {

struct TrainingImage {
    cv::Mat gray;  ///< 8-bit, one channel
    Shape68 truth;
};

/// One regression sample: an image and the shape the cascade is at for it.
struct TrainingSample {
    int image = 0;
    Shape68 shape;
};

struct LbfTrainingOptions {
    int stages = 7;
    int trees_per_landmark = 4;
    int tree_depth = 5;
    /// Feature sampling radius per stage, in units of the mean shape's
    /// outer-eye-corner distance; shrinks stage by stage. The last value
    /// repeats for any further stages.
    std::vector<float> radii = {0.5f, 0.35f, 0.25f, 0.18f, 0.13f, 0.1f, 0.08f};
    float hull_padding = 0.1f;          ///< feature points stay inside the hull grown by this factor
    int pool_size = 400;                ///< candidate feature points per landmark and stage
    int split_candidates = 300;         ///< point pairs tried at each split
    float tree_sample_fraction = 0.4f;  ///< share of the samples each tree is grown on
    float ridge = 15000.f;              ///< L2 weight of the global regression (docs/benchmarks.md: it matters most)
    int ridge_epochs = 4;               ///< block coordinate descent sweeps
    int threads = 2;
    std::uint64_t seed = 1;
    /// Progress: a label and a fraction 0..1 of the current step.
    std::function<void(const std::string&, double)> progress;
};

/// Mean shape (generalised Procrustes) and hull of the training shapes; no
/// stages, no box priors yet.
LbfModel prepareLbfModel(const std::vector<TrainingImage>& images, const LbfTrainingOptions& options);

/// Trains stage number model.stages.size() on the samples, appends it to the
/// model and moves every sample's shape by it. Deterministic for a given seed,
/// whatever the thread count.
void trainLbfStage(LbfModel& model, const std::vector<TrainingImage>& images, std::vector<TrainingSample>& samples,
                   const LbfTrainingOptions& options);

/// Mean 300-W NME of the samples' shapes against their images' truth.
double meanNme(const std::vector<TrainingImage>& images, const std::vector<TrainingSample>& samples);

/// Points of a feature pool for landmark l: uniform in the disc of `radius`
/// (mean-shape units) around it, kept inside the padded hull, written as
/// anchor combinations. Exposed for tests.
std::vector<FeaturePoint> sampleFeaturePool(const LbfModel& model, int landmark, float radius, int count, std::uint64_t seed);

}  // namespace facetrack::landmarks
