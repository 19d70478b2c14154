#pragma once
// The 1-euro filter (Casiez, Roussel, Vogel, "1 Euro Filter: A Simple
// Speed-based Low-pass Filter for Noisy Input in Interactive Systems", CHI 2012),
// element-wise over a vector:
//   x^_i = x^_{i-1} + alpha(f_c, dt) (x_i - x^_{i-1}),  alpha = 1 / (1 + 1 / (2 pi f_c dt)),
//   f_c  = f_min + f_extra + beta |dx^_i|,  dx^ the speed low-passed at f_d,
//   f_extra a cutoff the caller adds (0 in the paper; the filter stage's face motion).
// Slow motion gets a low cutoff (no jitter), fast motion a high one (little lag).

#include <Eigen/Core>

#include <utility>

namespace facetrack::core {

struct OneEuroSettings {
    double min_cutoff_hz = 1.0;         ///< f_min
    double beta = 1.0;                  ///< cutoff added per unit of speed (units of `scale` per second)
    double derivative_cutoff_hz = 1.0;  ///< f_d
};

class OneEuroFilter {
public:
    explicit OneEuroFilter(const OneEuroSettings& settings = {}) : settings_(settings) {}

    /// Filters the next sample, taken dt seconds after the previous one. Speed
    /// is measured in units of `scale` per second, so one setting serves pixels
    /// of faces of any size. The first sample (or one of another size) passes
    /// through. `extra_cutoff_hz` raises every element's cutoff by a speed
    /// measured elsewhere (the whole face's motion, MotionSpeed). Returns the
    /// filter's own state (valid until the next call); allocates only when the
    /// size changes.
    const Eigen::VectorXd& operator()(const Eigen::VectorXd& x, double dt, double scale = 1.0, double extra_cutoff_hz = 0.0);

    void reset() { value_.resize(0); }

    /// Per element i, f_min becomes s_i f_min (a vector of another size than
    /// the samples', or none: 1 for all): elements that move at different
    /// speeds (brows, lips) each get their own rest cutoff.
    void setMinCutoffScale(Eigen::VectorXd scale) { min_cutoff_scale_ = std::move(scale); }

private:
    OneEuroSettings settings_;
    Eigen::VectorXd value_, speed_;
    Eigen::VectorXd min_cutoff_scale_;
};

/// The speed of one point, |v^|, in units of `scale` per second: its raw
/// derivative low-passed at f_d, v^_i = v^_{i-1} + alpha(f_d, dt) ((p_i - p_{i-1}) / (dt scale) - v^_{i-1}).
/// For the centroid of many noisy points this is a far steadier measure of how
/// fast a face moves than any one point's speed.
class MotionSpeed {
public:
    explicit MotionSpeed(double derivativeCutoffHz = 1.0) : cutoff_hz_(derivativeCutoffHz) {}

    /// The speed after the next position, dt seconds after the previous one;
    /// 0 for the first (or after a bad time step).
    double operator()(const Eigen::Vector2d& p, double dt, double scale = 1.0);

    void reset() { started_ = false; }

private:
    double cutoff_hz_;
    bool started_ = false;
    Eigen::Vector2d last_ = Eigen::Vector2d::Zero(), speed_ = Eigen::Vector2d::Zero();
};

}  // namespace facetrack::core
