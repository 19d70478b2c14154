#include "data/dense/dense_fit.hpp"

#include "facetrack/error.hpp"
#include "fit/costs.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace facetrack::dense {

namespace {

double priorScale(const DenseModel& m) { return static_cast<double>(m.basis.slotCount()) / model::kLandmarkCount; }

double eyeDistance(const DenseModel& m, const Eigen::Matrix2Xd& observed) {
    return std::max((observed.col(m.eye_corner_slots[0]) - observed.col(m.eye_corner_slots[1])).norm(), 1.0);
}

std::vector<int> allSlots(const DenseModel& m) {
    std::vector<int> slots(static_cast<std::size_t>(m.basis.slotCount()));
    std::iota(slots.begin(), slots.end(), 0);
    return slots;
}

Eigen::Matrix3Xd baseShape(const DenseModel& m, const Eigen::VectorXd& identity) {
    return fit::shapeWithIdentity(m.basis, identity.size() == m.basis.identityCount() ? identity : Eigen::VectorXd());
}

/// Frontal, rolled like the eye line, at the depth where the model's eye
/// corners are as far apart as the observed ones, centred on the points.
fit::FaceParams coldStart(const DenseModel& m, const Eigen::Matrix3Xd& base, const core::Camera& camera, const Eigen::Matrix2Xd& observed) {
    fit::FaceParams p;
    p.expression = Eigen::VectorXd::Zero(m.basis.expressionCount());
    const Eigen::Vector2d eyeLine = observed.col(m.eye_corner_slots[1]) - observed.col(m.eye_corner_slots[0]);
    const double modelEyes = (base.col(m.eye_corner_slots[0]) - base.col(m.eye_corner_slots[1])).norm();
    const double depth = camera.fx * modelEyes / std::max(eyeLine.norm(), 1.0);
    p.pose.head<3>() = Eigen::Vector3d(0, 0, std::atan2(eyeLine.y(), eyeLine.x()));
    const Eigen::Vector2d centre2 = observed.rowwise().mean();
    const Eigen::Vector3d centre3 = fit::rotationOf(p.omega()) * base.rowwise().mean();
    p.pose.tail<3>() = Eigen::Vector3d((centre2.x() - camera.cx) * depth / camera.fx, (centre2.y() - camera.cy) * depth / camera.fy,
                                       depth) -
                       Eigen::Vector3d(centre3.x(), centre3.y(), 0.0);
    return p;
}

/// The frame's residual blocks: points (identity as a parameter, from the plain neutral) and the expression prior.
void addFrame(ceres::Problem& problem, const DenseModel& m, const DenseFitSettings& settings, DenseFrame& frame, double& scale,
              double* identity) {
    scale = eyeDistance(m, frame.observed);
    auto* cost = new fit::PointsCost({&m.basis, &m.basis.neutral, &frame.camera, frame.observed.data(), &scale, settings.huber},
                                     allSlots(m), true);
    double* expression = frame.params.expression.data();
    problem.AddResidualBlock(cost, nullptr, frame.params.pose.data(), expression, identity);
    Eigen::VectorXd weights(m.basis.expressionCount());
    for (Eigen::Index k = 0; k < weights.size(); ++k)
        weights[k] = priorScale(m) * (m.observable[static_cast<std::size_t>(k)] ? settings.observable_l2 : settings.unobservable_l2);
    problem.AddResidualBlock(new fit::ShrinkToZero(weights), nullptr, expression);
    for (int k = 0; k < m.basis.expressionCount(); ++k) {
        problem.SetParameterLowerBound(expression, k, 0.0);
        problem.SetParameterUpperBound(expression, k, 1.0);
    }
}

double rmsResidual(const DenseModel& m, const Eigen::VectorXd& identity, const DenseFrame& frame) {
    const Eigen::Matrix2Xd projected = projectPoints(m, identity, frame.camera, frame.params);
    return std::sqrt((projected - frame.observed).colwise().squaredNorm().mean()) / eyeDistance(m, frame.observed);
}

}  // namespace

Eigen::Matrix2Xd projectPoints(const DenseModel& m, const Eigen::VectorXd& identity, const core::Camera& camera,
                               const fit::FaceParams& params) {
    Eigen::Matrix3Xd x;
    fit::slotPositions(m.basis, baseShape(m, identity), params.expression, x);
    const Eigen::Matrix3d rotation = fit::rotationOf(params.omega());
    Eigen::Matrix2Xd out(2, x.cols());
    for (Eigen::Index i = 0; i < x.cols(); ++i) out.col(i) = camera.project<double>(rotation * x.col(i) + params.translation());
    return out;
}

DenseModel denseModel(const model::FaceModelData& data, const Correspondence& c, const std::vector<int>& expressions) {
    const std::vector<int> vertices = c.usableVertices();
    std::vector<fit::SurfacePoint> points;
    for (const int v : vertices) points.push_back(c.points[static_cast<std::size_t>(v)]);
    DenseModel m;
    m.basis = fit::buildPointBasis(data, points, expressions);
    const std::vector<int> observable = fit::observableExpressions(data, points);
    for (const int e : expressions) m.observable.push_back(std::find(observable.begin(), observable.end(), e) != observable.end());
    for (std::size_t s = 0; s < vertices.size(); ++s)
        m.basis.neutral.col(static_cast<Eigen::Index>(s)) += fit::modelToFrontal() * c.offsets_cm.col(vertices[s]);
    for (int side = 0; side < 2; ++side) {
        const auto it = std::find(vertices.begin(), vertices.end(), kCanonicalEyeCorners[side]);
        if (it == vertices.end())
            throw Error("the outer eye corner vertex " + std::to_string(kCanonicalEyeCorners[side]) + " has no surface point");
        m.eye_corner_slots[static_cast<std::size_t>(side)] = static_cast<int>(it - vertices.begin());
    }
    return m;
}

std::vector<int> labelledExpressions(const model::FaceModelData& data) {
    std::vector<int> out;
    for (int e = 0; e < static_cast<int>(data.expressions.size()); ++e)
        if (data.expressions[static_cast<std::size_t>(e)].name.rfind("eyeLook", 0) != 0) out.push_back(e);
    return out;
}

DenseFrame teacherFrame(const TeacherMeshes& meshes, int row, const std::vector<int>& vertices) {
    DenseFrame f;
    const auto r = static_cast<std::size_t>(row);
    f.camera = core::cameraFor(meshes.width[r], meshes.height[r], 60.0, 0.0);
    const Eigen::Matrix2Xd all = meshes.points(row);
    f.observed.resize(2, static_cast<Eigen::Index>(vertices.size()));
    for (std::size_t i = 0; i < vertices.size(); ++i) f.observed.col(static_cast<Eigen::Index>(i)) = all.col(vertices[i]);
    return f;
}

Eigen::Matrix3Xd learnTeacherConvention(DenseModel& m, const DenseFitSettings& settings, std::vector<DenseFrame> frames,
                                        const std::vector<int>& mirror, int rounds) {
    DenseFitSettings poseOnly = settings;
    poseOnly.observable_l2 = poseOnly.unobservable_l2 = 1.0;
    const int n = m.basis.slotCount();
    Eigen::Matrix3Xd total = Eigen::Matrix3Xd::Zero(3, n);
    for (int round = 0; round < rounds; ++round) {
        std::vector<std::vector<Eigen::Vector3d>> moves(static_cast<std::size_t>(n));
        for (DenseFrame& f : frames) {
            std::vector<DenseFrame> one{f};
            const Eigen::VectorXd identity = fitIdentity(m, poseOnly, one);
            if (!(one[0].residual < 0.1)) continue;  // a failed fit says nothing about the convention
            Eigen::Matrix3Xd x;
            fit::slotPositions(m.basis, baseShape(m, identity), one[0].params.expression, x);
            const Eigen::Matrix3d rotation = fit::rotationOf(one[0].params.omega());
            const Eigen::Matrix2Xd projected = projectPoints(m, identity, f.camera, one[0].params);
            for (int i = 0; i < n; ++i) {
                const Eigen::Vector3d p = rotation * x.col(i) + one[0].params.translation();
                const Eigen::Vector2d d = f.observed.col(i) - projected.col(i);
                moves[static_cast<std::size_t>(i)].push_back(
                    rotation.transpose() * Eigen::Vector3d(d.x() * p.z() / f.camera.fx, d.y() * p.z() / f.camera.fy, 0.0));
            }
        }
        Eigen::Matrix3Xd step(3, n);
        for (int i = 0; i < n; ++i) {
            auto& v = moves[static_cast<std::size_t>(i)];
            for (int c = 0; c < 3; ++c) {
                std::vector<double> values;
                for (const auto& move : v) values.push_back(move[c]);
                if (values.empty()) values.push_back(0.0);
                std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2), values.end());
                step(c, i) = values[values.size() / 2];
            }
        }
        // Symmetric, like the annotation convention: each offset averaged with its mirror's, x negated.
        Eigen::Matrix3Xd symmetric(3, n);
        for (int i = 0; i < n; ++i) {
            Eigen::Vector3d other = step.col(mirror[static_cast<std::size_t>(i)]);
            other.x() = -other.x();
            symmetric.col(i) = 0.5 * (step.col(i) + other);
        }
        m.basis.neutral += symmetric;
        total += symmetric;
    }
    return total;
}

DenseFrame canonicalFrame(const Correspondence& c, const Eigen::Matrix3Xd& canonical, const std::vector<int>& vertices, double yawDeg) {
    DenseFrame frame;
    frame.camera = core::cameraFor(640, 480, 60.0, 0.0);
    const Eigen::Matrix3d turn = fit::rotationOf(fit::omegaFromEuler(Eigen::Vector3d(0.0, yawDeg, 0.0)));
    frame.observed.resize(2, static_cast<Eigen::Index>(vertices.size()));
    for (std::size_t i = 0; i < vertices.size(); ++i) {
        const Eigen::Vector3d onModel = c.scale * c.rotation * canonical.col(vertices[i]) + c.translation;
        const Eigen::Vector3d inCamera = turn * (fit::modelToFrontal() * onModel) + Eigen::Vector3d(0.0, 0.0, 60.0);
        frame.observed.col(static_cast<Eigen::Index>(i)) = frame.camera.project<double>(inCamera);
    }
    return frame;
}

void fitFrame(const DenseModel& m, const DenseFitSettings& settings, const Eigen::VectorXd& identity, DenseFrame& frame, bool warm) {
    Eigen::VectorXd a = identity.size() == m.basis.identityCount() ? identity : Eigen::VectorXd::Zero(m.basis.identityCount());
    if (!warm || frame.params.expression.size() != m.basis.expressionCount()) {
        frame.params = coldStart(m, baseShape(m, a), frame.camera, frame.observed);
        warm = false;
    }
    ceres::Problem problem;
    double scale = 1.0;
    addFrame(problem, m, settings, frame, scale, a.data());
    problem.SetParameterBlockConstant(a.data());
    ceres::Solver::Summary summary;
    if (!warm) {
        problem.SetParameterBlockConstant(frame.params.expression.data());
        ceres::Solve(fit::solverOptions(settings.iterations, ceres::DENSE_QR, 1e-6), &problem, &summary);
        problem.SetParameterBlockVariable(frame.params.expression.data());
    }
    ceres::Solve(fit::solverOptions(settings.iterations, ceres::DENSE_QR, 1e-6), &problem, &summary);
    frame.residual = frame.params.pose.allFinite() && frame.params.expression.allFinite() ? rmsResidual(m, a, frame)
                                                                                          : std::numeric_limits<double>::infinity();
}

Eigen::VectorXd fitIdentity(const DenseModel& m, const DenseFitSettings& settings, std::vector<DenseFrame>& frames) {
    Eigen::VectorXd identity = Eigen::VectorXd::Zero(m.basis.identityCount());
    if (frames.empty()) return identity;
    for (DenseFrame& f : frames) fitFrame(m, settings, identity, f, false);
    ceres::Problem problem;
    std::vector<double> scales(frames.size());
    problem.AddResidualBlock(
        new fit::ShrinkToZero(m.basis.identityCount(), settings.identity_prior * priorScale(m) * static_cast<double>(frames.size())),
        nullptr, identity.data());
    for (std::size_t f = 0; f < frames.size(); ++f) addFrame(problem, m, settings, frames[f], scales[f], identity.data());
    ceres::Solver::Summary summary;
    ceres::Solve(fit::solverOptions(settings.iterations, frames.size() > 1 ? ceres::DENSE_SCHUR : ceres::DENSE_QR, 1e-6), &problem,
                 &summary);
    if (!identity.allFinite()) identity.setZero();
    for (DenseFrame& f : frames) f.residual = rmsResidual(m, identity, f);
    return identity;
}

}  // namespace facetrack::dense
