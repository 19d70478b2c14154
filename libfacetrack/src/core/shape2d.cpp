#include "core/shape2d.hpp"

#include "facetrack/error.hpp"

#include <cmath>

namespace facetrack::core {

Eigen::Matrix2f Similarity::linear() const {
    const float c = std::cos(angle), s = std::sin(angle);
    Eigen::Matrix2f m;
    m << c, -s, s, c;
    return scale * m;
}

Shape2 Similarity::apply(const Shape2& shape) const { return (linear() * shape).colwise() + translation; }

Similarity Similarity::inverse() const {
    Similarity inv;
    inv.scale = 1.f / scale;
    inv.angle = -angle;
    inv.translation = -(inv.linear() * translation);
    return inv;
}

Similarity alignSimilarity(const Shape2& from, const Shape2& to) {
    if (from.cols() != to.cols() || from.cols() < 2) throw Error("alignSimilarity: shapes of different sizes");
    const Eigen::Vector2f muFrom = from.rowwise().mean(), muTo = to.rowwise().mean();
    const Shape2 a = from.colwise() - muFrom, b = to.colwise() - muTo;
    // For complex numbers z = x + iy the optimum is s e^{i theta} = sum conj(a) b / sum |a|^2.
    const float dot = (a.array() * b.array()).sum();
    const float cross = (a.row(0).array() * b.row(1).array() - a.row(1).array() * b.row(0).array()).sum();
    const float norm = a.squaredNorm();
    Similarity t;
    if (norm <= 0.f) return t;
    t.scale = std::hypot(dot, cross) / norm;
    t.angle = std::atan2(cross, dot);
    t.translation = muTo - t.linear() * muFrom;
    return t;
}

namespace {
Shape2 normalised(const Shape2& shape) {
    const Shape2 centred = shape.colwise() - shape.rowwise().mean();
    const float rms = std::sqrt(centred.squaredNorm() / static_cast<float>(shape.cols()));
    return rms > 0.f ? Shape2(centred / rms) : centred;
}
}  // namespace

Shape2 procrustesMean(const std::vector<Shape2>& shapes, int iterations) {
    if (shapes.empty()) throw Error("procrustesMean: no shapes");
    Shape2 mean = normalised(shapes.front());
    for (int it = 0; it < iterations; ++it) {
        Shape2 sum = Shape2::Zero(2, mean.cols());
        for (const auto& s : shapes) sum += alignSimilarity(s, mean).apply(s);
        mean = normalised(sum);
    }
    return mean;
}

float nme68(const Shape2& predicted, const Shape2& truth) {
    if (predicted.cols() != 68 || truth.cols() != 68) throw Error("nme68: shapes must have 68 points");
    const float interocular = (truth.col(36) - truth.col(45)).norm();
    if (!(interocular > 0.f)) throw Error("nme68: coincident eye corners");
    return (predicted - truth).colwise().norm().mean() / interocular;
}

}  // namespace facetrack::core
