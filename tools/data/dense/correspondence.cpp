#include "data/dense/correspondence.hpp"

#include "facetrack/error.hpp"

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include <limits>

namespace facetrack::dense {

int Correspondence::usableCount() const { return static_cast<int>(std::count(usable.begin(), usable.end(), true)); }

std::vector<int> Correspondence::usableVertices() const {
    std::vector<int> out;
    for (std::size_t i = 0; i < points.size(); ++i)
        if (usable[i]) out.push_back(static_cast<int>(i));
    return out;
}

// Ericson, "Real-Time Collision Detection", 5.1.5: the Voronoi region of p.
Eigen::Vector3d closestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
    const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
    const Eigen::Vector3d bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        const double v = d1 / (d1 - d3);
        return {1 - v, v, 0};
    }
    const Eigen::Vector3d cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        const double w = d2 / (d2 - d6);
        return {1 - w, 0, w};
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return {0, 1 - w, w};
    }
    const double denom = 1.0 / (va + vb + vc);
    const double v = vb * denom, w = vc * denom;
    return {1 - v - w, v, w};
}

namespace {

/// The face-region surface of the model with identity a (model frame, cm).
Eigen::Matrix3Xd faceVertices(const model::FaceModelData& data, const Eigen::VectorXd& identity) {
    const auto n = static_cast<Eigen::Index>(data.face_vertex_count);
    Eigen::Matrix3Xd v = data.neutral.leftCols(n).cast<double>();
    if (identity.size() > 0) {
        const Eigen::VectorXd offsets = data.identity_basis.topRows(3 * n).cast<double>() * identity;
        v += Eigen::Map<const Eigen::Matrix3Xd>(offsets.data(), 3, n);
    }
    return v;
}

struct Nearest {
    fit::SurfacePoint point;
    Eigen::Vector3d position;
    double distance = std::numeric_limits<double>::infinity();
};

Nearest nearestOnSurface(const Eigen::Vector3d& p, const Eigen::Matrix3Xd& v, const std::vector<model::Triangle>& triangles) {
    Nearest best;
    for (const auto& t : triangles) {
        const Eigen::Vector3d a = v.col(t[0]), b = v.col(t[1]), c = v.col(t[2]);
        // A cheap bound first: p is further than the triangle's bounding sphere allows.
        const Eigen::Vector3d centre = (a + b + c) / 3.0;
        const double radius = std::max({(a - centre).norm(), (b - centre).norm(), (c - centre).norm()});
        if ((p - centre).norm() - radius >= best.distance) continue;
        const Eigen::Vector3d w = closestOnTriangle(p, a, b, c);
        const Eigen::Vector3d q = w[0] * a + w[1] * b + w[2] * c;
        const double d = (p - q).norm();
        if (d < best.distance) {
            best.distance = d;
            best.position = q;
            best.point.vertices = t;
            best.point.weights = w;
        }
    }
    return best;
}

}  // namespace

Correspondence buildCorrespondence(const model::FaceModelData& data, const Eigen::Matrix3Xd& canonical, int iterations) {
    std::vector<model::Triangle> face;
    for (const auto& t : data.triangles) {
        if (t[0] < data.face_vertex_count && t[1] < data.face_vertex_count && t[2] < data.face_vertex_count) face.push_back(t);
    }
    if (face.empty() || canonical.cols() == 0) throw Error("buildCorrespondence: empty face region or canonical mesh");
    const auto n = canonical.cols();
    const int k = data.identityCount();
    constexpr double kIdentityPrior = 1e-2;  // cm^2 per unit |a|^2, summed over all points

    Correspondence c;
    c.identity = Eigen::VectorXd::Zero(k);
    // Start: the outer eye corners (MediaPipe 33, 263; landmarks 36, 45) matched
    // in midpoint and distance; both frames share their axes.
    Eigen::Matrix3Xd surface = faceVertices(data, c.identity);
    {
        const Eigen::Vector3d right = canonical.col(kCanonicalEyeCorners[0]), left = canonical.col(kCanonicalEyeCorners[1]);
        const Eigen::Vector3d modelRight = data.neutral.col(data.landmark_vertices[36]).cast<double>();
        const Eigen::Vector3d modelLeft = data.neutral.col(data.landmark_vertices[45]).cast<double>();
        c.scale = (modelLeft - modelRight).norm() / (left - right).norm();
        c.translation = 0.5 * (modelLeft + modelRight) - c.scale * 0.5 * (left + right);
    }
    std::vector<Nearest> nearest(static_cast<std::size_t>(n));
    Eigen::Matrix3Xd aligned(3, n), target(3, n);
    for (int it = 0; it <= iterations; ++it) {
        aligned = (c.scale * c.rotation * canonical).colwise() + c.translation;
        for (Eigen::Index i = 0; i < n; ++i) {
            nearest[static_cast<std::size_t>(i)] = nearestOnSurface(aligned.col(i), surface, face);
            target.col(i) = nearest[static_cast<std::size_t>(i)].position;
        }
        if (it == iterations) break;
        // Trim the worst 10 %: the canonical face's rim has no counterpart.
        std::vector<double> d(static_cast<std::size_t>(n));
        for (Eigen::Index i = 0; i < n; ++i) d[static_cast<std::size_t>(i)] = nearest[static_cast<std::size_t>(i)].distance;
        std::vector<double> sorted = d;
        std::nth_element(sorted.begin(), sorted.begin() + n * 9 / 10, sorted.end());
        const double cut = sorted[static_cast<std::size_t>(n * 9 / 10)];
        std::vector<Eigen::Index> inliers;
        for (Eigen::Index i = 0; i < n; ++i)
            if (d[static_cast<std::size_t>(i)] <= cut) inliers.push_back(i);
        const auto m = static_cast<Eigen::Index>(inliers.size());
        Eigen::Matrix3Xd from(3, m), to(3, m);
        for (Eigen::Index j = 0; j < m; ++j) {
            from.col(j) = canonical.col(inliers[j]);
            to.col(j) = target.col(inliers[j]);
        }
        const Eigen::Matrix4d similarity = Eigen::umeyama(from, to, true);
        c.rotation = similarity.topLeftCorner<3, 3>();
        c.scale = c.rotation.col(0).norm();
        c.rotation /= c.scale;
        c.translation = similarity.topRightCorner<3, 1>();
        // Identity: the surface points move by B_i a (barycentric rows) towards the aligned vertices.
        Eigen::MatrixXd a(3 * m, k);
        Eigen::VectorXd r(3 * m);
        for (Eigen::Index j = 0; j < m; ++j) {
            const auto& p = nearest[static_cast<std::size_t>(inliers[j])].point;
            Eigen::MatrixXd rows = Eigen::MatrixXd::Zero(3, k);
            Eigen::Vector3d base = Eigen::Vector3d::Zero();
            for (int q = 0; q < 3; ++q) {
                rows += p.weights[q] * data.identity_basis.middleRows<3>(3 * p.vertices[q]).cast<double>();
                base += p.weights[q] * data.neutral.col(p.vertices[q]).cast<double>();
            }
            a.middleRows<3>(3 * j) = rows;
            r.segment<3>(3 * j) = c.scale * c.rotation * canonical.col(inliers[j]) + c.translation - base;
        }
        Eigen::MatrixXd normal = a.transpose() * a;
        normal.diagonal().array() += kIdentityPrior;
        c.identity = normal.ldlt().solve(a.transpose() * r);
        surface = faceVertices(data, c.identity);
    }
    c.points.resize(static_cast<std::size_t>(n));
    c.distance_cm.resize(static_cast<std::size_t>(n));
    c.usable.resize(static_cast<std::size_t>(n));
    c.offsets_cm = aligned - target;
    for (Eigen::Index i = 0; i < n; ++i) {
        const auto& best = nearest[static_cast<std::size_t>(i)];
        c.points[static_cast<std::size_t>(i)] = best.point;
        c.distance_cm[static_cast<std::size_t>(i)] = best.distance;
        c.usable[static_cast<std::size_t>(i)] = best.distance < kMaxDistanceCm;
    }
    return c;
}

}  // namespace facetrack::dense
