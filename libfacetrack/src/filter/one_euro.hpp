#pragma once
// The 1-euro filter (Casiez, Roussel, Vogel, "1 Euro Filter: A Simple
// Speed-based Low-pass Filter for Noisy Input in Interactive Systems", CHI 2012),
// element-wise over a vector:
//   x^_i = x^_{i-1} + alpha(f_c, dt) (x_i - x^_{i-1}),  alpha = 1 / (1 + 1 / (2 pi f_c dt)),
//   f_c  = f_min + beta |dx^_i|,  dx^ the speed low-passed at f_d.
// Slow motion gets a low cutoff (no jitter), fast motion a high one (little lag).

#include <Eigen/Core>

namespace facetrack::filter {

struct OneEuroSettings {
    double min_cutoff_hz = 1.0;   ///< f_min
    double beta = 1.0;            ///< cutoff added per unit of speed (units of `scale` per second)
    double derivative_cutoff_hz = 1.0;  ///< f_d
};

class OneEuroFilter {
public:
    explicit OneEuroFilter(const OneEuroSettings& settings = {}) : settings_(settings) {}

    /// Filters the next sample, taken dt seconds after the previous one. Speed
    /// is measured in units of `scale` per second, so one setting serves pixels
    /// of faces of any size. The first sample (or one of another size) passes
    /// through. Returns the filter's own state (valid until the next call);
    /// allocates only when the size changes.
    const Eigen::VectorXd& operator()(const Eigen::VectorXd& x, double dt, double scale = 1.0);

    void reset() { value_.resize(0); }

private:
    OneEuroSettings settings_;
    Eigen::VectorXd value_, speed_;
};

}  // namespace facetrack::filter
