#include "expression/face_warp.hpp"

#include "facetrack/error.hpp"
#include "fit/face_fitter.hpp"

#include <opencv2/imgproc.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

namespace facetrack::expression {

namespace {

/// Barycentric weights of p in triangle (a, b, c).
Eigen::Vector3d barycentric(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
    const Eigen::Vector2d v0 = b - a, v1 = c - a, v2 = p - a;
    const double d = v0.x() * v1.y() - v1.x() * v0.y();
    if (std::abs(d) < 1e-12) return {-1, -1, -1};
    const double u = (v2.x() * v1.y() - v1.x() * v2.y()) / d;
    const double v = (v0.x() * v2.y() - v2.x() * v0.y()) / d;
    return {1.0 - u - v, u, v};
}

}  // namespace

WarpLayout makeWarpLayout(const model::FaceModelData& data, const std::vector<int>& expressions, int size, int grid) {
    if (size < 16 || grid < 4) throw Error("makeWarpLayout: patch size >= 16 and grid >= 4 expected");
    WarpLayout layout;
    layout.size = size;
    // Frontal projection of the mean face: model (x, y) with y up -> patch (x, -y).
    auto frontal = [&](std::uint32_t v) { return Eigen::Vector2d(data.neutral(0, v), -data.neutral(1, v)); };
    std::vector<cv::Point2f> hullInput;
    for (const auto v : data.landmark_vertices)
        hullInput.emplace_back(static_cast<float>(frontal(v).x()), static_cast<float>(frontal(v).y()));
    std::vector<cv::Point2f> hull;
    cv::convexHull(hullInput, hull);
    cv::Point2f centre(0, 0);
    for (const auto& p : hull) centre += p * (1.0f / static_cast<float>(hull.size()));
    for (auto& p : hull) p = centre + 1.1f * (p - centre);
    float x0 = hull[0].x, y0 = hull[0].y, x1 = x0, y1 = y0;
    for (const auto& p : hull) x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
    const cv::Rect2f box(x0, y0, x1 - x0, y1 - y0);
    // One vertex per grid cell, the one nearest the cell's centre; only front-facing ones
    // (ahead of the eye corners' depth minus 3 cm: not the cheeks' far sides).
    const double minZ = std::min(data.neutral(2, data.landmark_vertices[36]), data.neutral(2, data.landmark_vertices[45])) - 3.0;
    std::vector<std::uint32_t> chosen(static_cast<std::size_t>(grid * grid), std::numeric_limits<std::uint32_t>::max());
    std::vector<double> best(chosen.size(), std::numeric_limits<double>::infinity());
    for (std::uint32_t v = 0; v < data.face_vertex_count; ++v) {
        const Eigen::Vector2d p = frontal(v);
        if (data.neutral(2, v) < minZ ||
            cv::pointPolygonTest(hull, cv::Point2f(static_cast<float>(p.x()), static_cast<float>(p.y())), false) < 0)
            continue;
        const double gx = (p.x() - box.x) / box.width * grid, gy = (p.y() - box.y) / box.height * grid;
        const int cx = std::clamp(static_cast<int>(gx), 0, grid - 1), cy = std::clamp(static_cast<int>(gy), 0, grid - 1);
        const double d = std::hypot(gx - (cx + 0.5), gy - (cy + 0.5));
        const auto cell = static_cast<std::size_t>(cy * grid + cx);
        if (d < best[cell]) best[cell] = d, chosen[cell] = v;
    }
    std::vector<fit::SurfacePoint> anchors;
    for (const auto v : chosen) {
        if (v == std::numeric_limits<std::uint32_t>::max()) continue;
        fit::SurfacePoint p;
        p.vertices = {v, v, v};
        anchors.push_back(p);
    }
    layout.anchors = fit::buildPointBasis(data, anchors, expressions);
    layout.centre = layout.anchors.neutral.rowwise().mean();
    // Patch coordinates: the grown hull's box fills the patch but a 6 % margin, aspect kept.
    const double margin = 0.06 * size;
    const double scale = (size - 2 * margin) / std::max(box.width, box.height);
    const Eigen::Vector2d offset(size / 2.0 - scale * (box.x + box.width / 2.0), size / 2.0 - scale * (box.y + box.height / 2.0));
    const int n = layout.anchors.slotCount();
    std::vector<Eigen::Vector2d> points;
    for (int i = 0; i < n; ++i) points.push_back(offset + scale * frontal(anchors[static_cast<std::size_t>(i)].vertices[0]));
    // Boundary: the grown hull itself (which the anchors only approach), and the patch border.
    for (const auto& p : hull) points.push_back(offset + scale * Eigen::Vector2d(p.x, p.y));
    const double e = size - 0.5, m = (size - 1) / 2.0;
    for (const auto& [x, y] :
         std::vector<std::pair<double, double>>{{-0.5, -0.5}, {m, -0.5}, {e, -0.5}, {e, m}, {e, e}, {m, e}, {-0.5, e}, {-0.5, m}})
        points.emplace_back(x, y);
    layout.canonical.resize(2, static_cast<Eigen::Index>(points.size()));
    for (std::size_t i = 0; i < points.size(); ++i) layout.canonical.col(static_cast<Eigen::Index>(i)) = points[i];

    cv::Subdiv2D subdiv(cv::Rect(-2, -2, size + 4, size + 4));
    for (const auto& p : points) subdiv.insert(cv::Point2f(static_cast<float>(p.x()), static_cast<float>(p.y())));
    std::vector<cv::Vec6f> triangles;
    subdiv.getTriangleList(triangles);
    auto indexOf = [&](float x, float y) {
        for (std::size_t i = 0; i < points.size(); ++i)
            if (std::abs(points[i].x() - x) < 1e-3 && std::abs(points[i].y() - y) < 1e-3) return static_cast<int>(i);
        return -1;
    };
    for (const auto& t : triangles) {
        const std::array<int, 3> tri = {indexOf(t[0], t[1]), indexOf(t[2], t[3]), indexOf(t[4], t[5])};
        if (tri[0] >= 0 && tri[1] >= 0 && tri[2] >= 0) layout.triangles.push_back(tri);
    }
    layout.pixel_triangle.assign(static_cast<std::size_t>(size * size), -1);
    layout.pixel_weights.assign(static_cast<std::size_t>(size * size), Eigen::Vector3f::Zero());
    for (int y = 0; y < size; ++y) {
        for (int x = 0; x < size; ++x) {
            const Eigen::Vector2d p(x, y);
            for (std::size_t t = 0; t < layout.triangles.size(); ++t) {
                const auto& tri = layout.triangles[t];
                const Eigen::Vector3d w = barycentric(p, points[static_cast<std::size_t>(tri[0])], points[static_cast<std::size_t>(tri[1])],
                                                      points[static_cast<std::size_t>(tri[2])]);
                if (w.minCoeff() < -1e-9) continue;
                layout.pixel_triangle[static_cast<std::size_t>(y * size + x)] = static_cast<int>(t);
                layout.pixel_weights[static_cast<std::size_t>(y * size + x)] = w.cast<float>();
                break;
            }
        }
    }
    Eigen::MatrixXd a(layout.anchorCount(), 3);
    a << layout.canonical.leftCols(layout.anchorCount()).transpose(), Eigen::VectorXd::Ones(layout.anchorCount());
    layout.affine_solve = (a.transpose() * a).inverse() * a.transpose();
    return layout;
}

Eigen::Matrix2Xd projectAnchors(const WarpLayout& layout, const Eigen::VectorXd& identity, const core::Camera& camera,
                                const fit::FaceParams& params) {
    const Eigen::Matrix3Xd base = fit::shapeWithIdentity(layout.anchors,
                                                         identity.size() == layout.anchors.identityCount() ? identity : Eigen::VectorXd());
    Eigen::Matrix3Xd work;
    Eigen::Matrix2Xd out;
    projectAnchors(layout, base, camera, params, work, out);
    return out;
}

void projectAnchors(const WarpLayout& layout, const Eigen::Matrix3Xd& identityShape, const core::Camera& camera,
                    const fit::FaceParams& params, Eigen::Matrix3Xd& work, Eigen::Matrix2Xd& out) {
    fit::slotPositions(layout.anchors, identityShape, params.expression, work);
    const Eigen::Matrix3d rotation = fit::rotationOf(params.omega());
    out.resize(2, work.cols());
    for (Eigen::Index i = 0; i < work.cols(); ++i) out.col(i) = camera.project<double>(rotation * work.col(i) + params.translation());
}

void warpFace(const WarpLayout& layout, const cv::Mat& frame, const Eigen::Matrix2Xd& anchors, cv::Mat& patch) {
    if (frame.type() != CV_8UC1 || frame.empty()) throw Error("warpFace: expected an 8-bit grey frame");
    const int n = layout.anchorCount();
    if (anchors.cols() != n || !anchors.allFinite()) throw Error("warpFace: expected " + std::to_string(n) + " finite anchor positions");
    // Boundary points follow the least-squares affine map canonical -> frame of the anchors.
    Eigen::Matrix<double, 3, 2> affine;
    affine.noalias() = layout.affine_solve * anchors.transpose();
    const auto framePoint = [&](int i) -> Eigen::Vector2d {
        if (i < n) return anchors.col(i);
        return affine.transpose() * Eigen::Vector3d(layout.canonical(0, i), layout.canonical(1, i), 1.0);
    };
    patch.create(layout.size, layout.size, CV_8UC1);
    const int w = frame.cols, h = frame.rows;
    for (int y = 0; y < layout.size; ++y) {
        auto* row = patch.ptr<std::uint8_t>(y);
        for (int x = 0; x < layout.size; ++x) {
            const auto k = static_cast<std::size_t>(y * layout.size + x);
            const int t = layout.pixel_triangle[k];
            if (t < 0) {
                row[x] = 0;
                continue;
            }
            const auto& tri = layout.triangles[static_cast<std::size_t>(t)];
            const Eigen::Vector3f& bw = layout.pixel_weights[k];
            const Eigen::Vector2d f = bw[0] * framePoint(tri[0]) + bw[1] * framePoint(tri[1]) + bw[2] * framePoint(tri[2]);
            const double u = f.x(), v = f.y();
            const double cu = std::clamp(u, 0.0, w - 1.0), cv = std::clamp(v, 0.0, h - 1.0);
            const int x0 = std::min(static_cast<int>(cu), w - 2 < 0 ? 0 : w - 2),
                      y0 = std::min(static_cast<int>(cv), h - 2 < 0 ? 0 : h - 2);
            const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
            const double fx = cu - x0, fy = cv - y0;
            const double top = (1 - fx) * frame.at<std::uint8_t>(y0, x0) + fx * frame.at<std::uint8_t>(y0, x1);
            const double bottom = (1 - fx) * frame.at<std::uint8_t>(y1, x0) + fx * frame.at<std::uint8_t>(y1, x1);
            row[x] = static_cast<std::uint8_t>(std::lround(std::clamp((1 - fy) * top + fy * bottom, 0.0, 255.0)));
        }
    }
}

}  // namespace facetrack::expression
