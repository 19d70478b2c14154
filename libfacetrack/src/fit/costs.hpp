#pragma once
// The residuals of the fit, with analytic Jacobians (the per-frame budget is
// well under a millisecond; automatic differentiation over ~50 expression
// weights would cost several times that).

#include "fit/camera.hpp"
#include "fit/fit_basis.hpp"

#include <ceres/ceres.h>

#include <array>

namespace facetrack::fit {

/// The 68 landmarks' reprojection errors, in units of the face size s (the
/// eye-corner distance in pixels), each under a Huber loss rho:
///   e_i = (pi(R(omega) X_i + t) - u_i) / s,   X_i = X0_i + D_i b [+ B_i a]
///   r_i = c(|e_i|^2) e_i,   c(q) = sqrt(rho(q) / q),   so that |r_i|^2 = rho(|e_i|^2),
///   rho(q) = q for q <= delta^2, else 2 delta sqrt(q) - delta^2,
/// with X0_i the slot's base shape (neutral with identity applied, or the
/// plain neutral when identity a is a parameter too), D_i and B_i its
/// expression and identity rows. The Jacobian is the exact one of r_i,
///   dr_i = (c I + 2 c'(q) e_i e_i^T) de_i,
/// so Gauss-Newton steps minimise sum rho exactly (test_fit's gradient check).
/// (One block for all landmarks, not 68 blocks under a Ceres loss: Ceres's
/// per-block bookkeeping cost more than the maths.)
/// Parameter blocks: pose (omega, t) [6], expression b [E], and, with
/// `withIdentity`, identity a [K]. The observations, scale, camera and base
/// are read through pointers, so one cost serves frame after frame; the jaw
/// landmarks' slots move along the contour.
class LandmarksCost final : public ceres::CostFunction {
public:
    static constexpr int kCount = model::kLandmarkCount;
    struct Inputs {
        const FitBasis* basis = nullptr;
        const Eigen::Matrix3Xd* base = nullptr;
        const Camera* camera = nullptr;
        const double* observed = nullptr;  ///< 2 x 68, column-major (u, v) pixels
        const double* scale = nullptr;
        double huber = 0.05;               ///< delta, in units of s
    };
    LandmarksCost(const Inputs& inputs, bool withIdentity);

    void setSlot(int landmark, int slot) { slots_[landmark] = slot; }

    bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

private:
    Inputs in_;
    std::array<int, kCount> slots_{};
    bool with_identity_;
};

/// r = sqrt(w) x: a zero-mean Gaussian prior on a parameter block (the L2 on
/// expressions, the identity prior). The warm fit's temporal priors are added
/// by FaceFitter::solveWarm itself.
class ShrinkToZero final : public ceres::CostFunction {
public:
    ShrinkToZero(int size, double weight);

    bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

private:
    int size_;
    double sqrt_weight_;
};

}  // namespace facetrack::fit
