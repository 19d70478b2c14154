#include "gaze/forest_training.hpp"

#include "facetrack/error.hpp"

#include <algorithm>
#include <atomic>
#include <cfloat>
#include <numeric>
#include <thread>

namespace facetrack::gaze {

namespace {

struct TreeBuilder {
    const std::vector<cv::Mat>& patches;
    const std::vector<PatchSample>& samples;
    const std::vector<float>& targets;
    int outputs;
    const ForestTrainingOptions& options;
    PatchFeature* splits;  // this tree's
    float* leaves;         // this tree's
    std::mt19937 rng;

    float value(const PatchFeature& f, int s) const {
        const PatchSample& p = samples[static_cast<std::size_t>(s)];
        return f.value(patches[static_cast<std::size_t>(p.patch)], p.x, p.y);
    }

    void meanInto(const std::vector<int>& idx, float* out) const {
        std::fill(out, out + outputs, 0.f);
        for (const int s : idx)
            for (int k = 0; k < outputs; ++k) out[k] += targets[static_cast<std::size_t>(s) * outputs + k];
        if (!idx.empty())
            for (int k = 0; k < outputs; ++k) out[k] /= static_cast<float>(idx.size());
    }

    /// Sets leaves below `node` (at `level`) to the samples' mean.
    void fillLeaves(int node, int level, const float* mean) {
        if (level == options.depth) {
            std::copy(mean, mean + outputs, leaves + static_cast<std::size_t>(node - ((1 << options.depth) - 1)) * outputs);
            return;
        }
        PatchFeature never;  // all samples go left: a Column test against a threshold no column reaches
        never.kind = PatchFeature::Column;
        never.threshold = FLT_MAX;
        splits[node] = never;
        fillLeaves(2 * node + 1, level + 1, mean);
        fillLeaves(2 * node + 2, level + 1, mean);
    }

    void build(int node, int level, std::vector<int>& idx) {
        std::vector<float> mean(static_cast<std::size_t>(outputs));
        meanInto(idx, mean.data());
        if (level == options.depth || static_cast<int>(idx.size()) < options.min_leaf) {
            fillLeaves(node, level, mean.data());
            return;
        }
        // The split search looks at a random subset of the node's samples.
        std::vector<int> search = idx;
        if (static_cast<int>(search.size()) > options.search_samples) {
            std::shuffle(search.begin(), search.end(), rng);
            search.resize(static_cast<std::size_t>(options.search_samples));
        }
        const int n = static_cast<int>(search.size());
        std::vector<double> total(static_cast<std::size_t>(outputs), 0.0);
        for (const int s : search)
            for (int k = 0; k < outputs; ++k) total[k] += targets[static_cast<std::size_t>(s) * outputs + k];
        double base = 0.0;
        for (const double t : total) base += t * t;
        base /= n;

        std::vector<float> values(static_cast<std::size_t>(n));
        std::vector<double> left(static_cast<std::size_t>(outputs));
        double bestGain = 1e-9;
        PatchFeature best;
        bool found = false;
        std::uniform_int_distribution<int> pick(0, n - 1);
        for (int c = 0; c < options.candidates; ++c) {
            PatchFeature f = options.draw(rng);
            for (int i = 0; i < n; ++i) values[static_cast<std::size_t>(i)] = value(f, search[static_cast<std::size_t>(i)]);
            for (int t = 0; t < options.thresholds; ++t) {
                const float threshold = values[static_cast<std::size_t>(pick(rng))];
                std::fill(left.begin(), left.end(), 0.0);
                int nLeft = 0;
                for (int i = 0; i < n; ++i) {
                    if (values[static_cast<std::size_t>(i)] >= threshold) continue;
                    ++nLeft;
                    const float* y = &targets[static_cast<std::size_t>(search[static_cast<std::size_t>(i)]) * outputs];
                    for (int k = 0; k < outputs; ++k) left[k] += y[k];
                }
                const int nRight = n - nLeft;
                if (nLeft < options.min_leaf / 2 + 1 || nRight < options.min_leaf / 2 + 1) continue;
                double sl = 0.0, sr = 0.0;
                for (int k = 0; k < outputs; ++k) {
                    sl += left[k] * left[k];
                    const double r = total[k] - left[k];
                    sr += r * r;
                }
                const double gain = sl / nLeft + sr / nRight - base;
                if (gain > bestGain) {
                    bestGain = gain;
                    best = f;
                    best.threshold = threshold;
                    found = true;
                }
            }
        }
        if (!found) {
            fillLeaves(node, level, mean.data());
            return;
        }
        splits[node] = best;
        std::vector<int> l, r;
        for (const int s : idx) (value(best, s) >= best.threshold ? r : l).push_back(s);
        idx.clear();
        idx.shrink_to_fit();
        build(2 * node + 1, level + 1, l);
        build(2 * node + 2, level + 1, r);
    }
};

}  // namespace

PatchForest trainPatchForest(const std::vector<cv::Mat>& patches, const std::vector<PatchSample>& samples,
                             const std::vector<float>& targets, int outputs, const ForestTrainingOptions& options) {
    if (samples.empty() || outputs < 1 || targets.size() != samples.size() * static_cast<std::size_t>(outputs))
        throw Error("trainPatchForest: no samples, or targets do not match them");
    if (!options.draw) throw Error("trainPatchForest: no test drawer");
    PatchForest forest;
    forest.depth = options.depth;
    forest.outputs = outputs;
    forest.splits.resize(static_cast<std::size_t>(options.trees) * static_cast<std::size_t>(forest.splitsPerTree()));
    forest.leaves.resize(static_cast<std::size_t>(options.trees) * static_cast<std::size_t>(forest.leavesPerTree()) * outputs);
    std::atomic<int> next{0}, done{0};
    const auto work = [&] {
        for (int t = next++; t < options.trees; t = next++) {
            TreeBuilder b{patches,
                          samples,
                          targets,
                          outputs,
                          options,
                          forest.splits.data() + static_cast<std::size_t>(t) * forest.splitsPerTree(),
                          forest.leaves.data() + static_cast<std::size_t>(t) * forest.leavesPerTree() * outputs,
                          std::mt19937(options.seed * 7919u + static_cast<unsigned>(t))};
            std::uniform_int_distribution<int> any(0, static_cast<int>(samples.size()) - 1);
            std::vector<int> bag(static_cast<std::size_t>(std::min<int>(options.samples_per_tree, static_cast<int>(samples.size()))));
            for (int& s : bag) s = any(b.rng);
            b.build(0, 0, bag);
            const int d = ++done;
            if (options.progress) options.progress(d, options.trees);
        }
    };
    std::vector<std::thread> threads;
    for (int i = 1; i < std::max(1, options.threads); ++i) threads.emplace_back(work);
    work();
    for (auto& t : threads) t.join();
    return forest;
}

}  // namespace facetrack::gaze
