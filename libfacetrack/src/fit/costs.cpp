#include "fit/costs.hpp"

#include <ceres/rotation.h>

namespace facetrack::fit {

LandmarkCost::LandmarkCost(const Inputs& inputs, const double* observed, int slot, bool withIdentity)
    : in_(inputs), observed_(observed), slot_(slot), with_identity_(withIdentity) {
    set_num_residuals(2);
    auto* sizes = mutable_parameter_block_sizes();
    sizes->push_back(6);
    sizes->push_back(in_.basis->expressionCount());
    if (with_identity_) sizes->push_back(in_.basis->identityCount());
}

bool LandmarkCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
    const FitBasis& basis = *in_.basis;
    const int expressions = basis.expressionCount();
    const int identities = basis.identityCount();
    const double* pose = parameters[0];
    const auto rowsD = basis.expression.middleRows<3>(3 * slot_);
    const auto rowsB = basis.identity.middleRows<3>(3 * slot_);

    Eigen::Vector3d x = in_.base->col(slot_);
    x.noalias() += rowsD * Eigen::Map<const Eigen::VectorXd>(parameters[1], expressions);
    if (with_identity_) x.noalias() += rowsB * Eigen::Map<const Eigen::VectorXd>(parameters[2], identities);

    // R(omega) x and its derivative in omega, by forward-mode differentiation
    // of Ceres's angle-axis rotation (exact, also away from omega = 0).
    using Jet3 = ceres::Jet<double, 3>;
    const Jet3 omega[3] = {Jet3(pose[0], 0), Jet3(pose[1], 1), Jet3(pose[2], 2)};
    const Jet3 point[3] = {Jet3(x.x()), Jet3(x.y()), Jet3(x.z())};
    Jet3 rotated[3];
    ceres::AngleAxisRotatePoint(omega, point, rotated);
    const Eigen::Vector3d y(rotated[0].a + pose[3], rotated[1].a + pose[4], rotated[2].a + pose[5]);
    if (!(y.z() > 1e-3)) return false;  // behind the camera: Ceres rejects the step

    const Camera& cam = *in_.camera;
    const double invScale = 1.0 / *in_.scale;
    const double invZ = 1.0 / y.z();
    residuals[0] = (cam.fx * y.x() * invZ + cam.cx - observed_[0]) * invScale;
    residuals[1] = (cam.fy * y.y() * invZ + cam.cy - observed_[1]) * invScale;
    if (!jacobians) return true;

    // d r / d y: the perspective projection's Jacobian, scaled.
    Eigen::Matrix<double, 2, 3> dProj;
    dProj << cam.fx * invZ, 0.0, -cam.fx * y.x() * invZ * invZ,  //
        0.0, cam.fy * invZ, -cam.fy * y.y() * invZ * invZ;
    dProj *= invScale;

    if (jacobians[0]) {
        Eigen::Map<Eigen::Matrix<double, 2, 6, Eigen::RowMajor>> j(jacobians[0]);
        Eigen::Matrix3d dOmega;
        for (int r = 0; r < 3; ++r) dOmega.row(r) = rotated[r].v.transpose();
        j.leftCols<3>() = dProj * dOmega;
        j.rightCols<3>() = dProj;
    }
    if (jacobians[1] || (with_identity_ && jacobians[2])) {
        Eigen::Matrix3d rotation;
        ceres::AngleAxisToRotationMatrix(pose, rotation.data());  // column-major
        const Eigen::Matrix<double, 2, 3> dX = dProj * rotation;
        if (jacobians[1]) {
            Eigen::Map<Eigen::Matrix<double, 2, Eigen::Dynamic, Eigen::RowMajor>>(jacobians[1], 2, expressions)
                .noalias() = dX * rowsD;
        }
        if (with_identity_ && jacobians[2]) {
            Eigen::Map<Eigen::Matrix<double, 2, Eigen::Dynamic, Eigen::RowMajor>>(jacobians[2], 2, identities)
                .noalias() = dX * rowsB;
        }
    }
    return true;
}

PullTowards::PullTowards(int size, const double* ref)
    : size_(size), ref_(ref), sqrt_weights_(Eigen::VectorXd::Zero(size)) {
    set_num_residuals(size);
    mutable_parameter_block_sizes()->push_back(size);
}

void PullTowards::setWeights(const Eigen::VectorXd& weights) { sqrt_weights_ = weights.cwiseMax(0.0).cwiseSqrt(); }

bool PullTowards::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
    for (int k = 0; k < size_; ++k) {
        residuals[k] = sqrt_weights_[k] * (parameters[0][k] - (ref_ ? ref_[k] : 0.0));
    }
    if (jacobians && jacobians[0]) {
        Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(jacobians[0], size_, size_) =
            sqrt_weights_.asDiagonal();
    }
    return true;
}

}  // namespace facetrack::fit
