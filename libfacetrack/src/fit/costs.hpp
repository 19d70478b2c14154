#pragma once
// The residuals of the fit, with analytic Jacobians (the per-frame budget is
// well under a millisecond; automatic differentiation over ~50 expression
// weights would cost several times that).

#include "core/camera.hpp"
#include "fit/fit_basis.hpp"

#include <ceres/ceres.h>

#include <vector>

namespace facetrack::fit {

/// Points' reprojection errors (the 68 landmarks, or the dense teacher's
/// points), in units of the face size s (the eye-corner distance in pixels),
/// each under a Huber loss rho:
///   e_i = (pi(R(omega) X_i + t) - u_i) / s,   X_i = X0_i + D_i b [+ B_i a]
///   r_i = w_i c(|e_i|^2) e_i,   c(q) = sqrt(rho(q) / q),   so that |r_i|^2 = w_i^2 rho(|e_i|^2),
///   rho(q) = q for q <= delta^2, else 2 delta sqrt(q) - delta^2,
/// with X0_i the slot's base shape (neutral with identity applied, or the
/// plain neutral when identity a is a parameter too), D_i and B_i its
/// expression and identity rows, w_i the point's factor (Inputs::weights; 1
/// without). The Jacobian is the exact one of r_i,
///   dr_i = w_i (c I + 2 c'(q) e_i e_i^T) de_i,
/// so Gauss-Newton steps minimise sum w_i^2 rho exactly (test_fit's gradient check).
/// (One block for all points, not one block each under a Ceres loss: Ceres's
/// per-block bookkeeping cost more than the maths.)
/// Parameter blocks: pose (omega, t) [6], expression b [E], and, with
/// `withIdentity`, identity a [K]. The observations, scale, camera and base
/// are read through pointers, so one cost serves frame after frame; point i
/// is slot slots[i] of the basis (the jaw landmarks' slots move along the contour).
class PointsCost final : public ceres::CostFunction {
public:
    struct Inputs {
        const PointBasis* basis = nullptr;
        const Eigen::Matrix3Xd* base = nullptr;
        const core::Camera* camera = nullptr;
        const double* observed = nullptr;  ///< 2 x N, column-major (u, v) pixels
        const double* scale = nullptr;
        double huber = 0.05;              ///< delta, in units of s
        const double* weights = nullptr;  ///< per point, a factor on its residual (the square root of its weight); null: all 1
    };
    PointsCost(const Inputs& inputs, std::vector<int> slots, bool withIdentity);

    void setSlot(int point, int slot) { slots_[static_cast<std::size_t>(point)] = slot; }
    int pointCount() const { return static_cast<int>(slots_.size()); }

    bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

private:
    Inputs in_;
    std::vector<int> slots_;
    bool with_identity_;
};

/// The slots of the 68 landmarks, the jaw at its own vertices.
std::vector<int> landmarkSlots(const FitBasis& basis);

/// r = sqrt(w) x: a zero-mean Gaussian prior on a parameter block (the L2 on
/// expressions, the identity prior). The warm fit's temporal priors are added
/// by FaceFitter::solveWarm itself.
/// With a weight per component: r_k = sqrt(w_k) x_k.
class ShrinkToZero final : public ceres::CostFunction {
public:
    ShrinkToZero(int size, double weight);
    explicit ShrinkToZero(const Eigen::VectorXd& weights);

    bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

private:
    Eigen::VectorXd sqrt_weights_;
};

}  // namespace facetrack::fit
