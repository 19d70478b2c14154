#pragma once
// Training PatchForests: each tree on a bootstrap sample, each node split by
// the candidate test that most reduces the squared error of the targets (for
// one-hot class targets that is the Gini impurity), thresholds drawn from the
// node's own values. Deterministic for a given seed.

#include "gaze/patch_forest.hpp"

#include <functional>
#include <random>
#include <vector>

namespace facetrack::gaze {

/// One training sample: a pixel (x, y) of patch `patch` (the anchor).
struct PatchSample {
    int patch = 0;
    int x = 0, y = 0;
};

struct ForestTrainingOptions {
    int trees = 8;
    int depth = 10;
    int candidates = 100;           ///< tests tried per node
    int thresholds = 6;             ///< thresholds tried per test
    int min_leaf = 8;               ///< a node with fewer samples is not split
    int samples_per_tree = 150000;  ///< bootstrap size
    int search_samples = 4000;      ///< samples a node's split search looks at (a random subset)
    int threads = 2;
    unsigned seed = 1;
    /// Draws a random test (its threshold is chosen by the trainer).
    std::function<PatchFeature(std::mt19937&)> draw;
    /// Called after each tree with (trees done, trees).
    std::function<void(int, int)> progress;
};

/// targets: samples.size() x outputs, row-major.
PatchForest trainPatchForest(const std::vector<cv::Mat>& patches, const std::vector<PatchSample>& samples,
                             const std::vector<float>& targets, int outputs, const ForestTrainingOptions& options);

}  // namespace facetrack::gaze
