#include "expression/update_net.hpp"

#include "facetrack/error.hpp"
#include "fit/fit_basis.hpp"

#include <algorithm>
#include <array>

namespace facetrack::expression {

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

UpdateMirror updateMirror(const std::vector<std::string>& expressions) {
    UpdateMirror m;
    m.order = {0, 1, 2, 3, 4, 5};
    m.sign = Eigen::VectorXd::Ones(6 + static_cast<Eigen::Index>(expressions.size()));
    m.sign.segment<3>(1).setConstant(-1.0);  // w_y, w_z, c_x
    for (const auto& name : expressions) {
        const std::string partner = fit::mirrorName(name);
        const auto it = std::find(expressions.begin(), expressions.end(), partner.empty() ? name : partner);
        if (it == expressions.end()) {
            throw Error("a mirror-averaged CNN stage needs " + name + "'s partner " + partner + " among its expressions");
        }
        m.order.push_back(6 + static_cast<int>(it - expressions.begin()));
    }
    return m;
}

bool refine(const WarpLayout& layout, nn::PatchNet& net, const cv::Mat& grey, const core::Camera& camera, fit::FaceParams& params,
            int rounds, RefineWork& work, const UpdateMirror* mirror) {
    constexpr double kMinDepthCm = 1.0;
    for (int i = 0; i < rounds; ++i) {
        if (!params.pose.allFinite() || centreOf(layout, params).z() < kMinDepthCm) return false;
        projectAnchors(layout, work.identity_shape, camera, params, work.anchors3d, work.anchors);
        if (!work.anchors.allFinite()) return false;
        warpFace(layout, grey, work.anchors, work.patch);
        if (!mirror) {
            applyUpdate(layout, net.predict(work.patch), params);
            continue;
        }
        cv::flip(work.patch, work.mirrored, 1);
        const std::array<cv::Mat, 2> both{work.patch, work.mirrored};
        const Eigen::VectorXd& out = net.predict(both);
        const Eigen::Index n = net.outputCount();
        work.update.resize(n);
        for (Eigen::Index k = 0; k < n; ++k) {
            work.update[k] = 0.5 * (out[k] + mirror->sign[k] * out[n + mirror->order[static_cast<std::size_t>(k)]]);
        }
        applyUpdate(layout, work.update, params);
    }
    return params.pose.allFinite() && centreOf(layout, params).z() >= kMinDepthCm;
}

}  // namespace facetrack::expression
