#include "fit/costs.hpp"

#include <ceres/rotation.h>

#include <algorithm>
#include <cmath>

namespace facetrack::fit {

std::vector<int> landmarkSlots(const FitBasis& basis) { return {basis.landmark_slots.begin(), basis.landmark_slots.end()}; }

PointsCost::PointsCost(const Inputs& inputs, std::vector<int> slots, bool withIdentity)
    : in_(inputs), slots_(std::move(slots)), with_identity_(withIdentity) {
    set_num_residuals(2 * pointCount());
    auto* sizes = mutable_parameter_block_sizes();
    sizes->push_back(6);
    sizes->push_back(in_.basis->expressionCount());
    if (with_identity_) sizes->push_back(in_.basis->identityCount());
}

bool PointsCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
    const PointBasis& basis = *in_.basis;
    const int count = pointCount();
    const int expressions = basis.expressionCount();
    const int identities = basis.identityCount();
    const double* pose = parameters[0];
    const Eigen::Map<const Eigen::VectorXd> b(parameters[1], expressions);
    const Eigen::Vector3d t(pose[3], pose[4], pose[5]);

    // R(omega) and dR/domega_k, by forward-mode differentiation of Ceres's
    // angle-axis conversion (exact, also away from omega = 0).
    using Jet3 = ceres::Jet<double, 3>;
    const Jet3 omega[3] = {Jet3(pose[0], 0), Jet3(pose[1], 1), Jet3(pose[2], 2)};
    Jet3 rJet[9];
    ceres::AngleAxisToRotationMatrix(omega, rJet);  // column-major
    Eigen::Matrix3d rotation;
    std::array<Eigen::Matrix3d, 3> dRotation;
    for (int k = 0; k < 9; ++k) {
        rotation(k % 3, k / 3) = rJet[k].a;
        for (int d = 0; d < 3; ++d) dRotation[d](k % 3, k / 3) = rJet[k].v[d];
    }

    const core::Camera& cam = *in_.camera;
    const double invScale = 1.0 / *in_.scale;
    const double delta2 = in_.huber * in_.huber;
    for (int i = 0; i < count; ++i) {
        const int slot = slots_[static_cast<std::size_t>(i)];
        const auto rowsD = basis.expression.middleRows<3>(3 * slot);
        Eigen::Vector3d x = in_.base->col(slot);
        x.noalias() += rowsD * b;
        if (with_identity_) {
            x.noalias() += basis.identity.middleRows<3>(3 * slot) * Eigen::Map<const Eigen::VectorXd>(parameters[2], identities);
        }
        const Eigen::Vector3d y = rotation * x + t;
        if (!(y.z() > 1e-3)) return false;  // behind the camera: Ceres rejects the step
        const double invZ = 1.0 / y.z();
        const Eigen::Vector2d e((cam.fx * y.x() * invZ + cam.cx - in_.observed[2 * i]) * invScale,
                                (cam.fy * y.y() * invZ + cam.cy - in_.observed[2 * i + 1]) * invScale);
        // Huber: rho(s) = s for s <= delta^2, else 2 delta sqrt(s) - delta^2;
        // r = c e with c = sqrt(rho(s) / s), so that |r|^2 = rho(s).
        const double s = e.squaredNorm();
        const bool inlier = s <= delta2;
        const double c = inlier ? 1.0 : std::sqrt((2.0 * in_.huber * std::sqrt(s) - delta2) / s);
        const double weight = in_.weights ? in_.weights[i] : 1.0;
        residuals[2 * i] = weight * c * e.x();
        residuals[2 * i + 1] = weight * c * e.y();
        if (!jacobians) continue;

        // dr/dy = (c I + 2 c'(s) e e^T) de/dy, c'(s) = (delta^2 / s^2 - delta / s^(3/2)) / (2 c),
        // with de/dy the perspective projection's Jacobian over the face size.
        Eigen::Matrix<double, 2, 3> dProj;
        dProj << cam.fx * invZ, 0.0, -cam.fx * y.x() * invZ * invZ,  //
            0.0, cam.fy * invZ, -cam.fy * y.y() * invZ * invZ;
        dProj *= invScale;
        if (!inlier) {
            const double dc = (delta2 / (s * s) - in_.huber / (s * std::sqrt(s))) / (2.0 * c);
            dProj = (c * Eigen::Matrix2d::Identity() + 2.0 * dc * e * e.transpose()) * dProj;
        }
        dProj *= weight;
        if (jacobians[0]) {
            Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor>> j(jacobians[0], 2 * count, 6);
            for (int d = 0; d < 3; ++d) j.block<2, 1>(2 * i, d) = dProj * (dRotation[d] * x);
            j.block<2, 3>(2 * i, 3) = dProj;
        }
        const Eigen::Matrix<double, 2, 3> dX = dProj * rotation;
        if (jacobians[1]) {
            Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(jacobians[1], 2 * count, expressions)
                .middleRows<2>(2 * i)
                .noalias() = dX * rowsD;
        }
        if (with_identity_ && jacobians[2]) {
            Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(jacobians[2], 2 * count, identities)
                .middleRows<2>(2 * i)
                .noalias() = dX * basis.identity.middleRows<3>(3 * slot);
        }
    }
    return true;
}

ShrinkToZero::ShrinkToZero(int size, double weight) : ShrinkToZero(Eigen::VectorXd::Constant(size, weight)) {}

ShrinkToZero::ShrinkToZero(const Eigen::VectorXd& weights) : sqrt_weights_(weights.cwiseMax(0.0).cwiseSqrt()) {
    set_num_residuals(static_cast<int>(weights.size()));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(weights.size()));
}

bool ShrinkToZero::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
    const auto n = sqrt_weights_.size();
    Eigen::Map<Eigen::VectorXd>(residuals, n) = sqrt_weights_.cwiseProduct(Eigen::Map<const Eigen::VectorXd>(parameters[0], n));
    if (jacobians && jacobians[0]) {
        Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(jacobians[0], n, n) = sqrt_weights_.asDiagonal();
    }
    return true;
}

}  // namespace facetrack::fit
