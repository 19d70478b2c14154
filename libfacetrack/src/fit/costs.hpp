#pragma once
// The residuals of the fit, with analytic Jacobians (the per-frame budget is
// well under a millisecond; automatic differentiation over ~50 expression
// weights would cost several times that).

#include "fit/camera.hpp"
#include "fit/fit_basis.hpp"

#include <ceres/ceres.h>

namespace facetrack::fit {

/// One landmark's reprojection error, in units of the face size s (the
/// eye-corner distance in pixels):
///   r = (pi(R(omega) X + t) - u) / s,   X = X_0 + D b [+ B a]
/// X_0 the slot's base shape (neutral with identity applied, or the plain
/// neutral when identity a is a parameter too), D and B its expression and
/// identity rows. Parameter blocks: pose (omega, t) [6], expression b [E],
/// and, with `withIdentity`, identity a [K].
/// The observation, scale, camera and base are read through pointers, so one
/// cost serves frame after frame; the slot can move along the jaw contour.
class LandmarkCost final : public ceres::CostFunction {
public:
    struct Inputs {
        const FitBasis* basis = nullptr;
        const Eigen::Matrix3Xd* base = nullptr;
        const Camera* camera = nullptr;
        const double* scale = nullptr;
    };
    LandmarkCost(const Inputs& inputs, const double* observed, int slot, bool withIdentity);

    void setSlot(int slot) { slot_ = slot; }
    int slot() const { return slot_; }

    bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

private:
    Inputs in_;
    const double* observed_;  // (u, v) pixels
    int slot_;
    bool with_identity_;
};

/// r = sqrt(w_k) (x_k - ref_k): a Gaussian prior on a parameter block, towards
/// zero (ref null) or towards values read through `ref` (the previous frame).
/// The weights can change between solves (zero switches the prior off).
class PullTowards final : public ceres::CostFunction {
public:
    PullTowards(int size, const double* ref);
    void setWeights(const Eigen::VectorXd& weights);  ///< one per element
    void setWeight(double weight) { setWeights(Eigen::VectorXd::Constant(size_, weight)); }

    bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

private:
    int size_;
    const double* ref_;
    Eigen::VectorXd sqrt_weights_;
};

}  // namespace facetrack::fit
