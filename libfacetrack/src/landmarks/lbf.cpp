#include "landmarks/lbf.hpp"

#include "core/shape2d.hpp"
#include "facetrack/error.hpp"

#include <array>

namespace facetrack::landmarks {

namespace {

/// A hint to bring memory into the cache; nothing where the compiler has no builtin for it.
inline void prefetch(const void* address) {
#if defined(__GNUC__) || defined(__clang__)
    __builtin_prefetch(address);
#else
    (void)address;
#endif
}

}  // namespace

Anchors anchorsOf(const LbfModel& model, const Shape68& shape) {
    Anchors anchors(2, model.anchorCount());
    anchors.leftCols<kLandmarks>() = shape;
    const Eigen::Vector2f centre = shape.rowwise().mean();
    const float grow = 1.f + model.hull_padding;
    for (std::size_t h = 0; h < model.hull_indices.size(); ++h) {
        anchors.col(kLandmarks + static_cast<Eigen::Index>(h)) = centre + grow * (shape.col(model.hull_indices[h]) - centre);
    }
    return anchors;
}

namespace {

#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
// One build for every x86-64, and AVX2's 8-wide int8 -> float conversions where the CPU has them:
// with SSE2 the sum below was a third of LBF's time.
#define FACETRACK_WITH_AVX2_CLONE __attribute__((target_clones("avx2", "default")))
#else
#define FACETRACK_WITH_AVX2_CLONE
#endif

/// increment += sum_k row_scale[r_k] * regression.row(r_k), rows r_k in the order given.
/// The rows are scattered over megabytes, so each is prefetched a few rows ahead of the sum.
FACETRACK_WITH_AVX2_CLONE
void sumRows(const LbfStage& stage, const int* rows, int count, float* increment) {
    constexpr int kAhead = 8;
    constexpr int kRowBytes = 2 * kLandmarks;  // int8 values
    for (int k = 0; k < std::min(count, kAhead); ++k) prefetch(stage.regression.row(rows[k]).data());
    for (int k = 0; k < count; ++k) {
        if (k + kAhead < count) {
            const auto* next = reinterpret_cast<const char*>(stage.regression.row(rows[k + kAhead]).data());
            for (int line = 0; line < kRowBytes; line += 64) prefetch(next + line);
        }
        const std::int8_t* q = stage.regression.row(rows[k]).data();
        const float scale = stage.row_scale[static_cast<std::size_t>(rows[k])];
        for (int c = 0; c < kRowBytes; ++c) increment[c] += scale * static_cast<float>(q[c]);
    }
}

}  // namespace

void applyStage(const LbfModel& model, const LbfStage& stage, const cv::Mat& gray, Shape68& shape) {
    const Anchors anchors = anchorsOf(model, shape);
    // Leaves first, then the rows.
    constexpr int kMaxTrees = kLandmarks * 64;
    std::array<int, kMaxTrees> rows;
    int count = 0;
    traverseStage(model, stage, gray, anchors, [&](int, int row) { rows[count++] = row; });
    std::array<float, 2 * kLandmarks> increment{};
    sumRows(stage, rows.data(), count, increment.data());
    // The increment is in the mean-shape frame: bring it back with M^{-1}'s linear part.
    const Eigen::Matrix2f back = core::alignSimilarity(shape, model.mean_shape).inverse().linear();
    shape += back * Eigen::Map<const Shape68>(increment.data());
}

Shape68 alignLandmarks(const LbfModel& model, const cv::Mat& gray, Shape68 shape) {
    for (const auto& stage : model.stages) applyStage(model, stage, gray, shape);
    return shape;
}

Shape68 alignFromStarts(const LbfModel& model, const cv::Mat& gray, const Shape68& start, int starts) {
    static constexpr float kDiagonal = 0.70710678f;
    static constexpr std::array<std::array<float, 2>, kMaxLandmarkStarts> kDirections = {{{0, 0},
                                                                                          {1, 0},
                                                                                          {-1, 0},
                                                                                          {0, 1},
                                                                                          {0, -1},
                                                                                          {kDiagonal, kDiagonal},
                                                                                          {-kDiagonal, -kDiagonal},
                                                                                          {kDiagonal, -kDiagonal},
                                                                                          {-kDiagonal, kDiagonal}}};
    starts = std::clamp(starts, 1, kMaxLandmarkStarts);
    const float shift = kStartShift * (start.col(36) - start.col(45)).norm();
    std::array<Shape68, kMaxLandmarkStarts> shapes;
    for (int k = 0; k < starts; ++k) {
        const auto& d = kDirections[static_cast<std::size_t>(k)];
        Shape68& shape = shapes[static_cast<std::size_t>(k)];
        shape = start;
        shape.row(0).array() += shift * d[0];
        shape.row(1).array() += shift * d[1];
    }
    // Stage by stage, all starts: they reach many of the same leaves, whose rows are then still in cache.
    for (const auto& stage : model.stages)
        for (int k = 0; k < starts; ++k) applyStage(model, stage, gray, shapes[static_cast<std::size_t>(k)]);
    Shape68 sum = Shape68::Zero();
    for (int k = 0; k < starts; ++k) sum += shapes[static_cast<std::size_t>(k)];
    return sum / static_cast<float>(starts);
}

void checkStartCount(int starts, const std::string& what) {
    if (starts < 1 || starts > kMaxLandmarkStarts) throw Error(what + " must be in 1.." + std::to_string(kMaxLandmarkStarts));
}

Shape68 shapeFromBox(const LbfModel& model, const Box& box, const std::string& detector) {
    const BoxPrior* prior = &model.box_priors.front();
    for (const auto& p : model.box_priors) {
        if (p.detector == detector) prior = &p;
    }
    Shape68 shape = prior->shape;
    shape.row(0) = shape.row(0).array() * box.width() + box.x0;
    shape.row(1) = shape.row(1).array() * box.height() + box.y0;
    return shape;
}

}  // namespace facetrack::landmarks
