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

Similarity Similarity::inverse() const {
    Similarity inv;
    inv.scale = 1.f / scale;
    inv.angle = -angle;
    inv.translation = -(inv.linear() * translation);
    return inv;
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

Eigen::VectorXf pointErrors68(const Shape2& predicted, const Shape2& truth) {
    if (predicted.cols() != 68 || truth.cols() != 68) throw Error("nme68: shapes must have 68 points");
    const float interocular = (truth.col(36) - truth.col(45)).norm();
    if (!(interocular > 0.f)) throw Error("nme68: coincident eye corners");
    return (predicted - truth).colwise().norm().transpose() / interocular;
}

float nme68(const Shape2& predicted, const Shape2& truth) { return pointErrors68(predicted, truth).mean(); }

float nmeBox(const Shape2& predicted, const Shape2& truth) {
    if (predicted.cols() != truth.cols() || truth.cols() == 0) throw Error("nmeBox: shapes must have the same, non-zero number of points");
    const Eigen::Vector2f size = truth.rowwise().maxCoeff() - truth.rowwise().minCoeff();
    const float scale = std::sqrt(size.x() * size.y());
    if (!(scale > 0.f)) throw Error("nmeBox: the truth's points have an empty box");
    return (predicted - truth).colwise().norm().mean() / scale;
}

Landmarks68 toLandmarks68(const Shape68& shape) {
    Landmarks68 out;
    for (int i = 0; i < kLandmarks; ++i) out[i] = {shape(0, i), shape(1, i)};
    return out;
}

Shape68 fromLandmarks68(const Landmarks68& points) {
    Shape68 shape;
    for (int i = 0; i < kLandmarks; ++i) shape.col(i) << points[i].x, points[i].y;
    return shape;
}

Box boundsOf(const Shape68& shape) {
    const Eigen::Vector2f lo = shape.rowwise().minCoeff(), hi = shape.rowwise().maxCoeff();
    return {lo.x(), lo.y(), hi.x(), hi.y()};
}

}  // namespace facetrack::core
