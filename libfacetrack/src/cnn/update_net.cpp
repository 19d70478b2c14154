#include "cnn/update_net.hpp"

#include "facetrack/error.hpp"

#include <algorithm>

namespace facetrack::cnn {

UpdateNet::UpdateNet(const std::string& onnx, int patchSize, int expressions, const std::string& what)
    : size_(patchSize), expressions_(expressions), update_(6 + expressions) {
    try {
        net_ = cv::dnn::readNetFromONNX(onnx.data(), onnx.size());
    } catch (const cv::Exception& e) {
        throw Error(what + " does not load: " + e.what());
    }
    if (net_.empty()) throw Error(what + " does not load");
    const int sizes[] = {1, 1, size_, size_};
    input_.create(4, sizes, CV_32F);
    input_.setTo(0);
    net_.setInput(input_);
    try {
        net_.forward(outputs_);
    } catch (const cv::Exception& e) {
        throw Error(what + " does not run on a " + std::to_string(size_) + " px patch: " + e.what());
    }
    if (outputs_.size() != 1 || static_cast<int>(outputs_[0].total()) != 6 + expressions_) {
        throw Error(what + " gives " + std::to_string(outputs_.empty() ? 0 : outputs_[0].total()) + " outputs, not 6 + " +
                    std::to_string(expressions_));
    }
}

const Eigen::VectorXd& UpdateNet::predict(const cv::Mat& patch) {
    if (patch.type() != CV_8UC1 || patch.rows != size_ || patch.cols != size_) throw Error("UpdateNet: the patch must be 8-bit grey, " + std::to_string(size_) + " square");
    cv::Scalar mean, sigma;
    cv::meanStdDev(patch, mean, sigma);
    const double scale = 1.0 / std::max(sigma[0], 255.0 * 1e-3);
    cv::Mat plane(size_, size_, CV_32F, input_.ptr<float>());
    patch.convertTo(plane, CV_32F, scale, -mean[0] * scale);
    net_.setInput(input_);
    net_.forward(outputs_);
    const float* out = outputs_[0].ptr<float>();
    for (int k = 0; k < update_.size(); ++k) update_[k] = out[k];
    return update_;
}

namespace {
Eigen::Vector3d centreOf(const WarpLayout& layout, const fit::FaceParams& p) {
    return fit::rotationOf(p.omega()) * layout.centre + p.translation();
}
}  // namespace

Eigen::VectorXd updateBetween(const WarpLayout& layout, const fit::FaceParams& start, const fit::FaceParams& face) {
    Eigen::VectorXd u(6 + start.expression.size());
    const Eigen::AngleAxisd turn(fit::rotationOf(face.omega()) * fit::rotationOf(start.omega()).transpose());
    u.head<3>() = turn.angle() * turn.axis();
    const Eigen::Vector3d from = centreOf(layout, start);
    u.segment<3>(3) = (centreOf(layout, face) - from) / from.z();
    u.tail(start.expression.size()) = face.expression - start.expression;
    return u;
}

void applyUpdate(const WarpLayout& layout, const Eigen::VectorXd& update, fit::FaceParams& params) {
    Eigen::Vector3d centre = centreOf(layout, params);
    centre += centre.z() * update.segment<3>(3);
    const Eigen::Matrix3d rotation = fit::rotationOf(update.head<3>()) * fit::rotationOf(params.omega());
    const Eigen::AngleAxisd r(rotation);
    params.pose.head<3>() = r.angle() * r.axis();
    params.pose.tail<3>() = centre - rotation * layout.centre;
    const Eigen::Index n = std::min<Eigen::Index>(params.expression.size(), update.size() - 6);
    for (Eigen::Index k = 0; k < n; ++k) params.expression[k] = std::clamp(params.expression[k] + update[6 + k], 0.0, 1.0);
}

bool refine(const WarpLayout& layout, UpdateNet& net, const cv::Mat& grey, const fit::Camera& camera, fit::FaceParams& params,
            int rounds, RefineWork& work) {
    constexpr double kMinDepthCm = 1.0;
    for (int i = 0; i < rounds; ++i) {
        if (!params.pose.allFinite() || centreOf(layout, params).z() < kMinDepthCm) return false;
        projectAnchors(layout, work.identity_shape, camera, params, work.anchors3d, work.anchors);
        if (!work.anchors.allFinite()) return false;
        warpFace(layout, grey, work.anchors, work.patch);
        applyUpdate(layout, net.predict(work.patch), params);
    }
    return params.pose.allFinite() && centreOf(layout, params).z() >= kMinDepthCm;
}

}  // namespace facetrack::cnn
