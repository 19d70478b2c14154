#include "cnn/update_net.hpp"

#include "facetrack/error.hpp"

#include <algorithm>

namespace facetrack::cnn {

namespace {
Eigen::Vector3d centreOf(const WarpLayout& layout, const fit::FaceParams& p) {
    return fit::rotationOf(p.omega()) * layout.centre + p.translation();
}
}  // namespace

void readParams(const HeadPose& pose, const std::vector<float>& native, const std::vector<int>& expressions, fit::FaceParams& params) {
    fit::poseParamsOf(pose, params);
    params.expression.resize(static_cast<Eigen::Index>(expressions.size()));
    for (std::size_t k = 0; k < expressions.size(); ++k) {
        const auto j = static_cast<std::size_t>(expressions[k]);
        params.expression[static_cast<Eigen::Index>(k)] = j < native.size() ? native[j] : 0.0;
    }
}

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

bool refine(const WarpLayout& layout, PatchNet& net, const cv::Mat& grey, const fit::Camera& camera, fit::FaceParams& params,
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
