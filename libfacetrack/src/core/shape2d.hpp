#pragma once
// 2D landmark shapes (2 x N, pixels): similarity alignment, mean shape, NME.

#include <Eigen/Core>

#include <vector>

namespace facetrack::core {

using Shape2 = Eigen::Matrix2Xf;

/// x -> scale * R(angle) * x + translation.
struct Similarity {
    float scale = 1.f;
    float angle = 0.f;  ///< radians
    Eigen::Vector2f translation = Eigen::Vector2f::Zero();

    Eigen::Matrix2f linear() const;
    Shape2 apply(const Shape2& shape) const;
    Similarity inverse() const;
};

/// The similarity that maps `from` onto `to` with least squared error
/// (Umeyama 1991, without reflection). Both shapes have the same point count.
Similarity alignSimilarity(const Shape2& from, const Shape2& to);

/// Generalised Procrustes mean: each shape aligned by similarity to the
/// current mean, iterated. The result is centred, with unit RMS radius.
Shape2 procrustesMean(const std::vector<Shape2>& shapes, int iterations = 5);

/// 300-W normalised mean error: mean point distance over the outer-eye-corner
/// distance (0-based points 36 and 45). Both shapes have 68 points.
float nme68(const Shape2& predicted, const Shape2& truth);

}  // namespace facetrack::core
