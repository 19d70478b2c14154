#include "gaze/patch_forest.hpp"

#include "facetrack/error.hpp"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace facetrack::gaze {

namespace {

/// A test's value at anchor (x, y); read(dx, dy) is the patch's pixel at (x + dx, y + dy).
template <class Read>
inline float valueOf(const PatchFeature& f, int x, int y, const Read& read) {
    switch (f.kind) {
        case PatchFeature::Difference:
            return read(f.ax, f.ay) - read(f.bx, f.by);
        case PatchFeature::Intensity:
            return read(f.ax, f.ay);
        case PatchFeature::Column:
            return static_cast<float>(x);
        case PatchFeature::Row:
            return static_cast<float>(y);
    }
    return 0.f;
}

/// out[0, outputs) = the mean over the forest's trees of the leaves reached from (x, y).
template <class Read>
void evaluateWith(const PatchForest& forest, int x, int y, const Read& read, float* out) {
    std::fill(out, out + forest.outputs, 0.f);
    const int trees = forest.treeCount(), perTree = forest.splitsPerTree();
    for (int t = 0; t < trees; ++t) {
        const PatchFeature* tree = forest.splits.data() + static_cast<std::size_t>(t) * static_cast<std::size_t>(perTree);
        int node = 0;
        for (int d = 0; d < forest.depth; ++d) {
            const PatchFeature& f = tree[node];
            node = 2 * node + (valueOf(f, x, y, read) >= f.threshold ? 2 : 1);
        }
        const float* values = forest.leaves.data() +
                              (static_cast<std::size_t>(t) * forest.leavesPerTree() + (node - perTree)) * forest.outputs;
        for (int k = 0; k < forest.outputs; ++k) out[k] += values[k];
    }
    if (trees > 0) {
        for (int k = 0; k < forest.outputs; ++k) out[k] /= static_cast<float>(trees);
    }
}

/// Reads the patch at (x + dx, y + dy), clamped to its edges.
auto clampedReader(const cv::Mat& patch, int x, int y) {
    return [&patch, x, y](int dx, int dy) {
        return patch.ptr<float>(std::clamp(y + dy, 0, patch.rows - 1))[std::clamp(x + dx, 0, patch.cols - 1)];
    };
}

}  // namespace

float PatchFeature::value(const cv::Mat& patch, int x, int y) const { return valueOf(*this, x, y, clampedReader(patch, x, y)); }

void PatchForest::evaluate(const cv::Mat& patch, int x, int y, float* out) const {
    evaluateWith(*this, x, y, clampedReader(patch, x, y), out);
}

void PatchForest::evaluatePadded(const cv::Mat& padded, int margin, int x, int y, float* out) const {
    const float* anchor = padded.ptr<float>(y + margin) + x + margin;
    const std::ptrdiff_t stride = static_cast<std::ptrdiff_t>(padded.step1());
    evaluateWith(
        *this, x, y, [anchor, stride](int dx, int dy) { return anchor[dy * stride + dx]; }, out);
}

int PatchForest::reach() const {
    int most = 0;
    for (const PatchFeature& f : splits) {
        if (f.kind == PatchFeature::Difference) most = std::max({most, std::abs(f.bx), std::abs(f.by)});
        if (f.kind <= PatchFeature::Intensity) most = std::max({most, std::abs(f.ax), std::abs(f.ay)});
    }
    return most;
}

void padPatch(const cv::Mat& patch, int margin, cv::Mat& padded) {
    cv::copyMakeBorder(patch, padded, margin, margin, margin, margin, cv::BORDER_REPLICATE);
}

void PatchForest::validate(const char* what) const {
    const auto fail = [&](const std::string& why) { throw Error(std::string(what) + ": corrupt: " + why); };
    if (depth < 1 || depth > 16 || outputs < 1 || outputs > 16) fail("forest depth or outputs");
    if (splits.empty() || splits.size() % static_cast<std::size_t>(splitsPerTree()) != 0) fail("split count");
    if (leaves.size() != static_cast<std::size_t>(treeCount()) * leavesPerTree() * outputs) fail("leaf count");
    for (const PatchFeature& f : splits) {
        if (f.kind > PatchFeature::Row || !std::isfinite(f.threshold)) fail("split");
    }
    for (const float v : leaves) {
        if (!std::isfinite(v)) fail("leaf value");
    }
}

}  // namespace facetrack::gaze
