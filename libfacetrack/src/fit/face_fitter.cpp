#include "fit/face_fitter.hpp"

#include "facetrack/error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace facetrack::fit {

namespace {

constexpr int kJaw = model::kContourLandmarkCount;

}  // namespace

ceres::Solver::Options solverOptions(int iterations, ceres::LinearSolverType solver, double tolerance) {
    ceres::Solver::Options options;
    options.linear_solver_type = solver;
    options.max_num_iterations = iterations;
    options.num_threads = 1;
    options.logging_type = ceres::SILENT;
    options.minimizer_progress_to_stdout = false;
    options.function_tolerance = tolerance;
    options.gradient_tolerance = 1e-8;
    options.parameter_tolerance = tolerance;
    return options;
}

namespace {

void boundExpressions(ceres::Problem& problem, double* expression, int count) {
    for (int k = 0; k < count; ++k) {
        problem.SetParameterLowerBound(expression, k, 0.0);
        problem.SetParameterUpperBound(expression, k, 1.0);
    }
}

Eigen::Matrix<double, 6, 1> poseTemporalWeights(const FitSettings& s) {
    Eigen::Matrix<double, 6, 1> w;
    w << Eigen::Vector3d::Constant(s.rotation_temporal), Eigen::Vector3d::Constant(s.translation_temporal);
    return w;
}

}  // namespace

bool isJawSide(int landmark) { return landmark < 6 || (landmark > 10 && landmark < kJaw); }

double jawSideWeight(const FitSettings& s, double yawDeg) {
    const double span = std::max(s.jaw_turn_to_deg - s.jaw_turn_from_deg, 1e-9);
    const double turned = std::clamp((std::abs(yawDeg) - s.jaw_turn_from_deg) / span, 0.0, 1.0);
    return 1.0 - turned * (1.0 - s.jaw_turned_weight);
}

namespace {

/// PointsCost's factor per landmark for a face at `yawDeg`: sqrt(jawSideWeight) on the jaw's sides, 1 elsewhere.
void setPointFactors(const FitSettings& settings, double yawDeg, std::array<double, model::kLandmarkCount>& factors) {
    const double jawSides = std::sqrt(jawSideWeight(settings, yawDeg));
    for (int i = 0; i < model::kLandmarkCount; ++i) factors[static_cast<std::size_t>(i)] = isJawSide(i) ? jawSides : 1.0;
}

}  // namespace

double eyeCornerDistance(const Landmarks2d& points) { return (points.col(36) - points.col(45)).norm(); }

double faceScale(const Landmarks2d& points) {
    const Eigen::Vector2d extent = points.rowwise().maxCoeff() - points.rowwise().minCoeff();
    return std::max({eyeCornerDistance(points), 0.5 * std::sqrt(extent.x() * extent.y()), 1.0});
}

void slotPositions(const PointBasis& basis, const Eigen::Matrix3Xd& base, const Eigen::VectorXd& expression, Eigen::Matrix3Xd& x) {
    x = base;
    if (expression.size() == basis.expressionCount() && expression.size() > 0) {
        Eigen::Map<Eigen::VectorXd>(x.data(), x.size()).noalias() += basis.expression * expression;
    }
}

Landmarks2d projectSlots(const FitBasis& basis, const Eigen::Matrix3Xd& x, const core::Camera& camera, const Pose6& pose,
                         const ContourSlots& contour) {
    const Eigen::Matrix3d rotation = rotationOf(pose.head<3>());
    Landmarks2d out;
    for (int i = 0; i < model::kLandmarkCount; ++i) {
        const int slot = i < kJaw ? contour[i] : basis.landmark_slots[i];
        out.col(i) = camera.project<double>(rotation * x.col(slot) + pose.tail<3>());
    }
    return out;
}

ContourSlots silhouetteContourAt(const FitBasis& basis, const Eigen::Matrix3Xd& x, const core::Camera& camera, const Pose6& pose) {
    const Eigen::Matrix3d rotation = rotationOf(pose.head<3>());
    auto projected = [&](const Eigen::Vector3d& p) { return camera.project<double>(rotation * p + pose.tail<3>()); };
    ContourSlots chosen{};
    // Some candidate paths wander along the outline, up the cheek or under the chin; those vertices
    // would win on reach and put a jaw point a jaw's height from its place.
    constexpr double kBandCm = 1.5;
    for (int i = 0; i < kJaw; ++i) {
        const Eigen::Vector3d own = x.col(basis.landmark_slots[i]);
        const Eigen::Vector2d origin = projected(own);
        const Eigen::Vector2d outward = (projected(own + basis.contour_outward[i]) - origin).normalized();
        const Eigen::Vector3d along = basis.contour_outward[i].cross(Eigen::Vector3d::UnitZ());  // the outline's direction, in the model
        chosen[i] = basis.landmark_slots[i];
        double best = -std::numeric_limits<double>::infinity();
        for (const int slot : basis.contour_slots[i]) {
            if (std::abs((x.col(slot) - own).dot(along)) > kBandCm) continue;
            const double reach = (projected(x.col(slot)) - origin).dot(outward);
            if (reach > best) {
                best = reach;
                chosen[i] = slot;
            }
        }
    }
    return chosen;
}

ContourSlots nearestContourAt(const FitBasis& basis, const Eigen::Matrix3Xd& x, const core::Camera& camera, const Pose6& pose,
                              const Landmarks2d& observed) {
    const Eigen::Matrix3d rotation = rotationOf(pose.head<3>());
    ContourSlots chosen{};
    for (int i = 0; i < kJaw; ++i) {
        chosen[i] = basis.landmark_slots[i];
        double best = std::numeric_limits<double>::infinity();
        for (const int slot : basis.contour_slots[i]) {
            const double d = (camera.project<double>(rotation * x.col(slot) + pose.tail<3>()) - observed.col(i)).squaredNorm();
            if (d < best) {
                best = d;
                chosen[i] = slot;
            }
        }
    }
    return chosen;
}

Landmarks2d projectLandmarks(const FitBasis& basis, const Eigen::Matrix3Xd& base, const core::Camera& camera, const FaceParams& params,
                             const ContourSlots& contour) {
    Eigen::Matrix3Xd x;
    slotPositions(basis, base, params.expression, x);
    return projectSlots(basis, x, camera, params.pose, contour);
}

ContourSlots silhouetteContour(const FitBasis& basis, const Eigen::Matrix3Xd& base, const core::Camera& camera, const FaceParams& params) {
    Eigen::Matrix3Xd x;
    slotPositions(basis, base, params.expression, x);
    return silhouetteContourAt(basis, x, camera, params.pose);
}

FaceFitter::FaceFitter(std::shared_ptr<const FitBasis> basis, const FitSettings& settings) : basis_(std::move(basis)), settings_(settings) {
    if (!basis_) throw Error("FaceFitter: no fit basis");
    const int expressions = basis_->expressionCount();
    base_ = basis_->neutral;
    slots_ = base_;
    previous_pose_.setZero();
    current_.expression = previous_expression_ = expression_before_step_ = Eigen::VectorXd::Zero(expressions);
    double* pose = current_.pose.data();
    double* expression = current_.expression.data();
    problem_ = std::make_unique<ceres::Problem>();
    point_weights_.fill(1.0);
    landmarks_ = new PointsCost({basis_.get(), &base_, &camera_, observed_.data(), &scale_, settings_.huber, point_weights_.data()},
                                landmarkSlots(*basis_), false);
    problem_->AddResidualBlock(landmarks_, nullptr, pose, expression);
    // Cold fits only: no previous frame, so no temporal prior here.
    expression_weights_ = basis_->expressionPriorWeights(settings_.expression_l2);
    problem_->AddResidualBlock(new ShrinkToZero(expression_weights_), nullptr, expression);
    boundExpressions(*problem_, expression, expressions);

    residuals_.resize(2 * model::kLandmarkCount);
    jacobian_pose_.resize(2 * model::kLandmarkCount, 6);
    jacobian_expression_.resize(2 * model::kLandmarkCount, expressions);
    jacobian_.resize(2 * model::kLandmarkCount, 6 + expressions);
}

FaceFitter::~FaceFitter() = default;

double FaceFitter::objective(Eigen::MatrixXd* jacobian) {
    const int e = basis_->expressionCount();
    const double* parameters[] = {current_.pose.data(), current_.expression.data()};
    double* blocks[] = {jacobian_pose_.data(), jacobian_expression_.data()};
    if (!landmarks_->Evaluate(parameters, residuals_.data(), jacobian ? blocks : nullptr)) {
        return std::numeric_limits<double>::infinity();
    }
    double cost = residuals_.squaredNorm();
    // The priors are diagonal quadratics, added here directly.
    const double wT = settings_.expression_temporal;
    const Eigen::VectorXd& b = current_.expression;
    cost += expression_weights_.dot(b.cwiseAbs2()) + wT * (b - previous_expression_).squaredNorm();
    const Eigen::Matrix<double, 6, 1> wP = poseTemporalWeights(settings_);
    cost += (wP.array() * (current_.pose - previous_pose_).array().square()).sum();
    if (jacobian) {
        jacobian->leftCols<6>() = jacobian_pose_;
        jacobian->rightCols(e) = jacobian_expression_;
    }
    return cost;
}

int FaceFitter::solveWarm(int iterations) {
    const int e = basis_->expressionCount();
    const double wT = settings_.expression_temporal;
    const Eigen::Matrix<double, 6, 1> wP = poseTemporalWeights(settings_);
    double cost = objective(&jacobian_);
    if (!std::isfinite(cost)) return 0;
    double lambda = 1e-4;
    int steps = 0;
    for (int it = 0; it < iterations; ++it) {
        // Gauss-Newton system of all residuals: landmarks, then the priors' diagonals.
        normal_.noalias() = jacobian_.transpose() * jacobian_;
        gradient_.noalias() = jacobian_.transpose() * residuals_;
        normal_.diagonal().head<6>() += wP;
        gradient_.head<6>() += wP.cwiseProduct(current_.pose - previous_pose_);
        normal_.diagonal().tail(e).array() += expression_weights_.array() + wT;
        gradient_.tail(e) += expression_weights_.cwiseProduct(current_.expression) + wT * (current_.expression - previous_expression_);

        const Pose6 pose = current_.pose;
        expression_before_step_ = current_.expression;
        bool accepted = false;
        for (int attempt = 0; attempt < 6 && !accepted; ++attempt) {
            damped_ = normal_;
            damped_.diagonal() *= 1.0 + lambda;
            step_ = ldlt_.compute(damped_).solve(-gradient_);
            current_.pose = pose + step_.head<6>();
            current_.expression = (expression_before_step_ + step_.tail(e)).cwiseMax(0.0).cwiseMin(1.0);  // projected onto the bounds
            const double next = objective(nullptr);
            if (next < cost) {
                accepted = true;
                lambda = std::max(lambda * 0.1, 1e-7);
                const bool converged = cost - next < 1e-5 * cost;
                cost = objective(&jacobian_);
                ++steps;
                if (converged) return steps;
            } else {
                lambda *= 10.0;
            }
        }
        if (!accepted) {
            current_.pose = pose;
            current_.expression = expression_before_step_;
            break;
        }
    }
    return steps;
}

void FaceFitter::setIdentity(const Eigen::VectorXd& identity) {
    if (identity.size() != 0 && identity.size() != basis_->identityCount()) {
        throw Error("FaceFitter: identity has " + std::to_string(identity.size()) + " coefficients, the model " +
                    std::to_string(basis_->identityCount()));
    }
    identity_ = identity;
    base_ = shapeWithIdentity(*basis_, identity_);
}

FaceParams FaceFitter::initialParams(const Landmarks2d& observed) const {
    // Frontal, rolled like the eye line, at the depth where the model's eye
    // corners are as far apart as the observed ones, centred on the inner points.
    FaceParams p;
    p.expression = Eigen::VectorXd::Zero(basis_->expressionCount());
    const Eigen::Vector2d eyeLine = observed.col(45) - observed.col(36);
    const double modelEyes = (base_.col(basis_->landmark_slots[36]) - base_.col(basis_->landmark_slots[45])).norm();
    const double depth = camera_.fx * modelEyes / std::max(eyeLine.norm(), 1.0);
    Eigen::Vector2d centre2 = Eigen::Vector2d::Zero();
    Eigen::Vector3d centre3 = Eigen::Vector3d::Zero();
    for (int i = kJaw; i < model::kLandmarkCount; ++i) {
        centre2 += observed.col(i);
        centre3 += base_.col(basis_->landmark_slots[i]);
    }
    const double n = model::kLandmarkCount - kJaw;
    centre2 /= n;
    centre3 /= n;
    p.pose.head<3>() = Eigen::Vector3d(0, 0, std::atan2(eyeLine.y(), eyeLine.x()));
    const Eigen::Vector3d rotatedCentre = rotationOf(p.omega()) * centre3;
    p.pose.tail<3>() = Eigen::Vector3d((centre2.x() - camera_.cx) * depth / camera_.fx, (centre2.y() - camera_.cy) * depth / camera_.fy,
                                       depth) -
                       Eigen::Vector3d(rotatedCentre.x(), rotatedCentre.y(), 0.0);
    return p;
}

int FaceFitter::solve(int iterations) {
    ceres::Solver::Summary summary;
    ceres::Solve(solverOptions(iterations, ceres::DENSE_NORMAL_CHOLESKY), problem_.get(), &summary);
    return static_cast<int>(summary.iterations.size());
}

void FaceFitter::chooseContour(bool nearest, FitReport& report) {
    slotPositions(*basis_, base_, current_.expression, slots_);
    report.contour = nearest ? nearestContourAt(*basis_, slots_, camera_, current_.pose, observed_)
                             : silhouetteContourAt(*basis_, slots_, camera_, current_.pose);
    for (int i = 0; i < kJaw; ++i) landmarks_->setSlot(i, report.contour[i]);
    setPointFactors(settings_, eulerDegrees(current_.omega()).y(), point_weights_);
}

FitReport FaceFitter::fit(const core::Camera& camera, const Landmarks2d& observed, FaceParams& params, bool warm) {
    FitReport report;
    report.residual = std::numeric_limits<double>::infinity();
    if (!observed.allFinite()) return report;
    camera_ = camera;
    observed_ = observed;
    scale_ = faceScale(observed);
    if (!warm || params.expression.size() != basis_->expressionCount()) {
        params = initialParams(observed);
        warm = false;
    }
    current_.pose = previous_pose_ = params.pose;
    current_.expression = previous_expression_ = params.expression;

    // Cold rounds start from the silhouette, which holds the pose steady while
    // it is far off; the last round (and every warm fit) takes the candidates
    // nearest the observed jaw points.
    if (warm) {
        chooseContour(true, report);
        report.iterations += solveWarm(settings_.warm_iterations);
    } else {
        // Pose alone first: from the frontal start, expressions would absorb the rotation.
        chooseContour(false, report);
        problem_->SetParameterBlockConstant(current_.expression.data());
        report.iterations += solve(settings_.cold_iterations);
        problem_->SetParameterBlockVariable(current_.expression.data());
        for (int round = 0; round < 2; ++round) {
            chooseContour(round == 1, report);
            report.iterations += solve(settings_.cold_iterations);
        }
    }
    params.pose = current_.pose;
    params.expression = current_.expression;
    slotPositions(*basis_, base_, params.expression, slots_);
    report.projected = projectSlots(*basis_, slots_, camera_, params.pose, report.contour);
    report.residual = std::sqrt((report.projected - observed).colwise().squaredNorm().mean()) / scale_;
    if (!params.pose.allFinite() || !params.expression.allFinite()) {
        report.residual = std::numeric_limits<double>::infinity();
    }
    return report;
}

Eigen::VectorXd calibrateIdentity(const FitBasis& basis, std::vector<CalibrationFrame>& frames, const FitSettings& settings) {
    const int expressions = basis.expressionCount();
    Eigen::VectorXd identity = Eigen::VectorXd::Zero(basis.identityCount());
    if (frames.empty()) return identity;

    ceres::Problem problem;
    std::vector<double> scales(frames.size());
    std::vector<std::array<double, model::kLandmarkCount>> weights(frames.size());
    problem.AddResidualBlock(new ShrinkToZero(basis.identityCount(), settings.identity_prior * static_cast<double>(frames.size())), nullptr,
                             identity.data());
    for (std::size_t f = 0; f < frames.size(); ++f) {
        auto& frame = frames[f];
        if (frame.params.expression.size() != expressions) frame.params.expression = Eigen::VectorXd::Zero(expressions);
        scales[f] = faceScale(frame.observed);
        setPointFactors(settings, eulerDegrees(frame.params.omega()).y(), weights[f]);
        auto* cost = new PointsCost(
            {&basis, &basis.neutral, &frame.camera, frame.observed.data(), &scales[f], settings.huber, weights[f].data()},
            landmarkSlots(basis), true);
        for (int i = 0; i < kJaw; ++i) cost->setSlot(i, frame.contour[i]);
        problem.AddResidualBlock(cost, nullptr, frame.params.pose.data(), frame.params.expression.data(), identity.data());
        problem.AddResidualBlock(new ShrinkToZero(basis.expressionPriorWeights(settings.expression_l2)), nullptr,
                                 frame.params.expression.data());
        boundExpressions(problem, frame.params.expression.data(), expressions);
    }
    ceres::Solver::Summary summary;
    ceres::Solve(solverOptions(50, ceres::DENSE_SCHUR), &problem, &summary);
    if (!identity.allFinite()) return Eigen::VectorXd::Zero(basis.identityCount());
    return identity;
}

}  // namespace facetrack::fit
