#include "expression/geometry_net.hpp"

#include "expression/lip_net.hpp"
#include "expression/update_net.hpp"
#include "facetrack/error.hpp"

#include <cmath>

namespace facetrack::expression {

Eigen::Matrix2f NormalisingFrame::unroll() const {
    Eigen::Matrix2f r;
    r << std::cos(theta), std::sin(theta), -std::sin(theta), std::cos(theta);
    return r;
}

NormalisingFrame normalisingFrame(const core::Shape68& points) {
    NormalisingFrame frame;
    frame.centre = points.rowwise().mean();
    const Eigen::Vector2f eyeLine = points.middleCols<6>(42).rowwise().mean() - points.middleCols<6>(36).rowwise().mean();
    frame.theta = std::atan2(eyeLine.y(), eyeLine.x());
    frame.rms = std::sqrt((points.colwise() - frame.centre).squaredNorm() / static_cast<float>(core::kLandmarks));
    return frame;
}

GeometryFeatures geometryFeatures(const core::Shape68& points, double pitchDeg, double yawDeg) {
    const NormalisingFrame frame = normalisingFrame(points);
    const core::Shape68 q = frame.unroll() * (points.colwise() - frame.centre) / frame.rms;
    GeometryFeatures f;
    f.head<2 * core::kLandmarks>() = Eigen::Map<const Eigen::Matrix<float, 2 * core::kLandmarks, 1>>(q.data());
    f[2 * core::kLandmarks] = static_cast<float>(std::sin(pitchDeg * M_PI / 180.0));
    f[2 * core::kLandmarks + 1] = static_cast<float>(std::sin(yawDeg * M_PI / 180.0));
    return f;
}

GeometryFeatures mirroredGeometryFeatures(const core::Shape68& points, double pitchDeg, double yawDeg) {
    core::Shape68 mirrored;
    for (int i = 0; i < core::kLandmarks; ++i) {
        const int from = core::kMirror68[static_cast<std::size_t>(i)];
        mirrored.col(i) << -points(0, from), points(1, from);
    }
    return geometryFeatures(mirrored, pitchDeg, -yawDeg);
}

GeometryNet::GeometryNet(std::vector<nn::DenseLayer> layers, const std::vector<std::string>& expressions) {
    for (const nn::DenseLayer& l : layers) {
        weights_.push_back(
            Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(l.weight.data(), l.rows, l.cols));
        biases_.push_back(Eigen::Map<const Eigen::VectorXf>(l.bias.data(), l.rows));
        activations_.emplace_back(l.rows);
    }
    for (const int i : updateMirror(expressions).order) {
        if (i >= 6) mirror_.push_back(i - 6);  // the update's first six values are the pose's
    }
    const int inputs = weights_.empty() ? 0 : static_cast<int>(weights_.front().cols());
    if (inputs != nn::kGeometryFeatures && inputs != nn::kGeometryFeatures + 2 * nn::kLipPoints)
        throw Error("geometry net: " + std::to_string(inputs) + " inputs, neither the landmarks' features nor those and the lips'");
    reads_lips_ = inputs != nn::kGeometryFeatures;
    input_.resize(inputs);
    direct_.resize(static_cast<Eigen::Index>(mirror_.size()));
    averaged_.resize(direct_.size());
}

const Eigen::VectorXf& GeometryNet::forward(const Eigen::VectorXf& f) {
    for (std::size_t i = 0; i < weights_.size(); ++i) {
        Eigen::VectorXf& a = activations_[i];
        if (i == 0) {
            a.noalias() = weights_[i] * f;
        } else {
            a.noalias() = weights_[i] * activations_[i - 1];
        }
        a += biases_[i];
        if (i + 1 < weights_.size()) {
            a = a.cwiseMax(0.f);
        } else {
            a = (1.f + (-a.array()).exp()).inverse().matrix();
        }
    }
    return activations_.back();
}

const Eigen::VectorXf& GeometryNet::predict(const core::Shape68& points, double pitchDeg, double yawDeg, const LipPoints* lips) {
    if (reads_lips_ && !lips) throw Error("geometry net: it reads the lips, and none were given");
    input_.head<nn::kGeometryFeatures>() = geometryFeatures(points, pitchDeg, yawDeg);
    if (reads_lips_) input_.tail<2 * nn::kLipPoints>() = lips->reshaped();
    direct_ = forward(input_);
    input_.head<nn::kGeometryFeatures>() = mirroredGeometryFeatures(points, pitchDeg, yawDeg);
    if (reads_lips_) input_.tail<2 * nn::kLipPoints>() = mirroredLips(*lips).reshaped();
    const Eigen::VectorXf& mirrored = forward(input_);
    for (Eigen::Index k = 0; k < direct_.size(); ++k) averaged_[k] = 0.5f * (direct_[k] + mirrored[mirror_[static_cast<std::size_t>(k)]]);
    return averaged_;
}

}  // namespace facetrack::expression
