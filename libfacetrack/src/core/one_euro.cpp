#include "core/one_euro.hpp"

#include "core/math.hpp"

#include <algorithm>
#include <cmath>

namespace facetrack::core {

namespace {

double alpha(double cutoffHz, double dt) {
    const double tau = 1.0 / (2.0 * core::kPi * cutoffHz);
    return 1.0 / (1.0 + tau / dt);
}

}  // namespace

const Eigen::VectorXd& OneEuroFilter::operator()(const Eigen::VectorXd& x, double dt, double scale, double extraCutoffHz) {
    if (value_.size() != x.size() || !value_.allFinite() || !(dt > 0.0)) {
        value_ = x;
        speed_.setZero(x.size());
        return value_;
    }
    scale = std::max(scale, 1e-9);
    const double aSpeed = alpha(settings_.derivative_cutoff_hz, dt);
    speed_ += aSpeed * ((x - value_) / (dt * scale) - speed_);
    for (Eigen::Index i = 0; i < x.size(); ++i) {
        const double scaled = min_cutoff_scale_.size() == x.size() ? min_cutoff_scale_[i] : 1.0;
        const double cutoff = scaled * settings_.min_cutoff_hz + extraCutoffHz + settings_.beta * std::abs(speed_[i]);
        value_[i] += alpha(cutoff, dt) * (x[i] - value_[i]);
    }
    return value_;
}

double MotionSpeed::operator()(const Eigen::Vector2d& p, double dt, double scale) {
    if (!started_ || !(dt > 0.0) || !p.allFinite() || !speed_.allFinite()) {
        speed_.setZero();
    } else {
        speed_ += alpha(cutoff_hz_, dt) * ((p - last_) / (dt * std::max(scale, 1e-9)) - speed_);
    }
    last_ = p;
    started_ = p.allFinite();
    return speed_.norm();
}

}  // namespace facetrack::core
