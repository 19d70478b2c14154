#pragma once
// 2D landmark shapes (2 x N, pixels): similarity alignment, mean shape, NME.

#include "facetrack/error.hpp"
#include "facetrack/geometry.hpp"

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <vector>

namespace facetrack::core {

using Shape2 = Eigen::Matrix2Xf;

constexpr int kLandmarks = 68;

/// A 68-point shape (iBUG order, pixels), fixed size so that per-frame work never allocates:
/// what the landmark stages pass each other.
using Shape68 = Eigen::Matrix<float, 2, kLandmarks>;

/// The 68-point iBUG index each point goes to in a mirrored image.
inline constexpr std::array<int, kLandmarks> kMirror68 = {
    16, 15, 14, 13, 12, 11, 10, 9,  8,  7,  6,  5,  4, 3, 2, 1, 0,  // jaw
    26, 25, 24, 23, 22, 21, 20, 19, 18, 17,                         // brows
    27, 28, 29, 30, 35, 34, 33, 32, 31,                             // nose
    45, 44, 43, 42, 47, 46, 39, 38, 37, 36, 41, 40,                 // eyes
    54, 53, 52, 51, 50, 49, 48, 59, 58, 57, 56, 55,                 // outer lips
    64, 63, 62, 61, 60, 67, 66, 65,                                 // inner lips
};

/// The shape as the public API's landmark array, and back.
Landmarks68 toLandmarks68(const Shape68& shape);
Shape68 fromLandmarks68(const Landmarks68& points);

/// The shape's bounding box.
Box boundsOf(const Shape68& shape);

/// x -> scale * R(angle) * x + translation.
struct Similarity {
    float scale = 1.f;
    float angle = 0.f;  ///< radians
    Eigen::Vector2f translation = Eigen::Vector2f::Zero();

    Eigen::Matrix2f linear() const;
    template <class S>
    auto apply(const Eigen::MatrixBase<S>& shape) const {
        return ((linear() * shape).colwise() + translation).eval();
    }
    Similarity inverse() const;
};

/// The similarity that maps `from` onto `to` with least squared error
/// (Umeyama 1991, without reflection). Both are 2 x N with the same N; with
/// fixed-size shapes nothing is allocated.
template <class From, class To>
Similarity alignSimilarity(const Eigen::MatrixBase<From>& from, const Eigen::MatrixBase<To>& to) {
    static_assert(From::RowsAtCompileTime == 2 && To::RowsAtCompileTime == 2);
    if (from.cols() != to.cols() || from.cols() < 2) throw Error("alignSimilarity: shapes of different sizes");
    const Eigen::Vector2f muFrom = from.rowwise().mean(), muTo = to.rowwise().mean();
    // With points as complex numbers z, the optimum s e^{i theta} is sum conj(a) b / sum |a|^2.
    float dot = 0.f, cross = 0.f, norm = 0.f;
    for (Eigen::Index i = 0; i < from.cols(); ++i) {
        const Eigen::Vector2f a = from.col(i) - muFrom, b = to.col(i) - muTo;
        dot += a.dot(b);
        cross += a.x() * b.y() - a.y() * b.x();
        norm += a.squaredNorm();
    }
    Similarity t;
    if (!(norm > 0.f)) return t;
    t.scale = std::hypot(dot, cross) / norm;
    t.angle = std::atan2(cross, dot);
    t.translation = muTo - t.linear() * muFrom;
    return t;
}

/// Generalised Procrustes mean: each shape aligned by similarity to the
/// current mean, iterated. The result is centred, with unit RMS radius.
Shape2 procrustesMean(const std::vector<Shape2>& shapes, int iterations = 5);

/// Outer-eye-corner distance (points 36 and 45): the 300-W face size, in pixels.
inline float eyeCornerDistance(const Landmarks68& p) { return std::hypot(p[36].x - p[45].x, p[36].y - p[45].y); }

/// 300-W normalised mean error: mean point distance over the outer-eye-corner
/// distance (0-based points 36 and 45). Both shapes have 68 points.
float nme68(const Shape2& predicted, const Shape2& truth);

/// Each point's error over the outer-eye-corner distance: nme68 is their mean.
Eigen::VectorXf pointErrors68(const Shape2& predicted, const Shape2& truth);

/// The iBUG 68-point regions, first and one-past-last point.
struct LandmarkRegion {
    const char* name;
    int first, end;
};
inline constexpr LandmarkRegion kRegions68[] = {{"jaw", 0, 17}, {"brows", 17, 27}, {"nose", 27, 36}, {"eyes", 36, 48}, {"mouth", 48, 68}};

/// Box-normalised mean error (AFLW2000-3D, large poses, where the eye corners
/// can coincide): mean point distance over sqrt(w h) of the truth's bounding box.
float nmeBox(const Shape2& predicted, const Shape2& truth);

}  // namespace facetrack::core
