#include "gaze/patch_forest.hpp"

#include "facetrack/error.hpp"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace facetrack::gaze {

namespace {
inline float at(const cv::Mat& patch, int x, int y) {
    x = std::clamp(x, 0, patch.cols - 1);
    y = std::clamp(y, 0, patch.rows - 1);
    return patch.ptr<float>(y)[x];
}
}  // namespace

float PatchFeature::value(const cv::Mat& patch, int x, int y) const {
    switch (kind) {
        case Difference: return at(patch, x + ax, y + ay) - at(patch, x + bx, y + by);
        case Intensity: return at(patch, x + ax, y + ay);
        case Column: return static_cast<float>(x);
        case Row: return static_cast<float>(y);
    }
    return 0.f;
}

int PatchForest::leaf(int t, const cv::Mat& patch, int x, int y) const {
    const PatchFeature* tree = splits.data() + static_cast<std::size_t>(t) * static_cast<std::size_t>(splitsPerTree());
    int node = 0;
    for (int d = 0; d < depth; ++d) {
        const PatchFeature& f = tree[node];
        node = 2 * node + (f.value(patch, x, y) >= f.threshold ? 2 : 1);
    }
    return node - splitsPerTree();
}

void PatchForest::evaluate(const cv::Mat& patch, int x, int y, float* out) const {
    std::fill(out, out + outputs, 0.f);
    const int trees = treeCount();
    for (int t = 0; t < trees; ++t) {
        const float* values = leaves.data() + (static_cast<std::size_t>(t) * leavesPerTree() + leaf(t, patch, x, y)) * outputs;
        for (int k = 0; k < outputs; ++k) out[k] += values[k];
    }
    if (trees > 0) {
        for (int k = 0; k < outputs; ++k) out[k] /= static_cast<float>(trees);
    }
}

void PatchForest::evaluatePadded(const cv::Mat& padded, int margin, int x, int y, float* out) const {
    const float* anchor = padded.ptr<float>(y + margin) + x + margin;
    const std::ptrdiff_t stride = static_cast<std::ptrdiff_t>(padded.step1());
    const auto at = [&](int dx, int dy) { return anchor[dy * stride + dx]; };
    std::fill(out, out + outputs, 0.f);
    const int trees = treeCount(), perTree = splitsPerTree();
    for (int t = 0; t < trees; ++t) {
        const PatchFeature* tree = splits.data() + static_cast<std::size_t>(t) * static_cast<std::size_t>(perTree);
        int node = 0;
        for (int d = 0; d < depth; ++d) {
            const PatchFeature& f = tree[node];
            float value = 0.f;
            switch (f.kind) {
                case PatchFeature::Difference: value = at(f.ax, f.ay) - at(f.bx, f.by); break;
                case PatchFeature::Intensity: value = at(f.ax, f.ay); break;
                case PatchFeature::Column: value = static_cast<float>(x); break;
                case PatchFeature::Row: value = static_cast<float>(y); break;
            }
            node = 2 * node + (value >= f.threshold ? 2 : 1);
        }
        const float* values = leaves.data() + (static_cast<std::size_t>(t) * leavesPerTree() + (node - perTree)) * outputs;
        for (int k = 0; k < outputs; ++k) out[k] += values[k];
    }
    if (trees > 0) {
        for (int k = 0; k < outputs; ++k) out[k] /= static_cast<float>(trees);
    }
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
