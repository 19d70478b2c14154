#include "gaze/gaze_fit.hpp"

#include "gaze/eye_model_data.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace facetrack::gaze {

namespace {
constexpr float kDeg = 3.14159265358979f / 180.f;
constexpr int kRegionW = kClassifiedRegion.columns();
constexpr int kRegionH = kClassifiedRegion.rows();
constexpr int kDataResiduals = kRegionW * kRegionH;
constexpr int kPriorResiduals = 2 + 4 + 4;  // binocular 2, temporal 4, ahead 4
constexpr int kResiduals = 2 * kDataResiduals + kPriorResiduals;

Eigen::Vector2f toPatch(const EyePatch& p, const Eigen::Vector2f& image) {
    const cv::Matx23f& a = p.patch_from_image;
    return {a(0, 0) * image.x() + a(0, 1) * image.y() + a(0, 2), a(1, 0) * image.x() + a(1, 1) * image.y() + a(1, 2)};
}

Eigen::Vector2f project(const fit::Camera& c, const Eigen::Vector3f& p) {
    return {static_cast<float>(c.fx) * p.x() / p.z() + static_cast<float>(c.cx),
            static_cast<float>(c.fy) * p.y() / p.z() + static_cast<float>(c.cy)};
}

/// Data residuals of one eye into r[0, kDataResiduals).
void dataResiduals(const EyeObservation& eye, const Eigen::Matrix3f& R, const fit::Camera& camera, const Eigen::Vector2f& angles,
                   float scale, float* r) {
    ProjectedIris iris;
    if (scale <= 0.f || !projectIris(eye, R, camera, angles, iris)) {
        std::fill(r, r + kDataResiduals, 0.f);
        return;
    }
    Eigen::Matrix2f axes;
    axes << iris.axis1, iris.axis2;
    const float det = axes.determinant();
    if (!(std::fabs(det) > 1e-6f)) {
        std::fill(r, r + kDataResiduals, 0.f);
        return;
    }
    const Eigen::Matrix2f inverse = axes.inverse();
    // Edge softness: about 0.7 patch pixels whatever the iris size.
    const float sharpness = 0.5f * (iris.axis1.norm() + iris.axis2.norm()) / 0.7f;
    for (int y = 0; y < kRegionH; ++y) {
        const float* pi = eye.iris->ptr<float>(y);
        const float* po = eye.open->ptr<float>(y);
        for (int x = 0; x < kRegionW; ++x) {
            const Eigen::Vector2f q(static_cast<float>(kClassifiedRegion.x(x)), static_cast<float>(kClassifiedRegion.y(y)));
            const float rho = (inverse * (q - iris.centre)).norm();
            const float inside = 1.f / (1.f + std::exp(-sharpness * (1.f - rho)));
            r[y * kRegionW + x] = scale * (pi[x] - inside * po[x]);
        }
    }
}

void priorResiduals(const GazeAngles& a, const GazeAngles& previous, bool havePrevious, const GazeFitSettings& s, float* p) {
    p[0] = (a[0].y() - a[1].y()) / (s.pitch_sigma_deg * kDeg);
    p[1] = (a[1].x() - a[0].x() - s.vergence_deg * kDeg) / (s.vergence_sigma_deg * kDeg);
    for (int e = 0; e < 2; ++e) {
        for (int k = 0; k < 2; ++k) {
            p[2 + 2 * e + k] = havePrevious ? (a[e][k] - previous[e][k]) / (s.temporal_sigma_deg * kDeg) : 0.f;
            p[6 + 2 * e + k] = a[e][k] / (s.ahead_sigma_deg * kDeg);
        }
    }
}

/// The iris probability's centroid back-projected onto the iris sphere: a
/// starting point that follows saccades without lag. False when there is too
/// little visible iris.
bool centroidGuess(const EyeObservation& eye, const Eigen::Matrix3f& R, const fit::Camera& camera, Eigen::Vector2f& angles) {
    double mass = 0, sx = 0, sy = 0;
    for (int y = 0; y < kRegionH; ++y) {
        const float* pi = eye.iris->ptr<float>(y);
        for (int x = 0; x < kRegionW; ++x) {
            const double m = pi[x] * pi[x];
            mass += m;
            sx += m * kClassifiedRegion.x(x);
            sy += m * kClassifiedRegion.y(y);
        }
    }
    // About four grid cells of certain iris.
    if (mass < 4.0) return false;
    const Point2 image = toImage(*eye.patch, {static_cast<float>(sx / mass), static_cast<float>(sy / mass)});
    // Ray through the pixel, nearest point on it to the eyeball centre, then onto the sphere of radius d_i.
    const Eigen::Vector3f ray = Eigen::Vector3f((image.x - static_cast<float>(camera.cx)) / static_cast<float>(camera.fx),
                                                (image.y - static_cast<float>(camera.cy)) / static_cast<float>(camera.fy), 1.f)
                                    .normalized();
    const float along = ray.dot(eye.centre);
    const Eigen::Vector3f closest = along * ray;
    const float miss = (closest - eye.centre).norm();
    const float back = std::sqrt(std::max(0.f, kIrisDistanceMm * kIrisDistanceMm - miss * miss));
    const Eigen::Vector3f onSphere = (along - back) * ray;  // the near side, towards the camera
    const Eigen::Vector3f head = R.transpose() * (onSphere - eye.centre).normalized();
    if (!head.allFinite() || head.z() <= 0.f) return false;
    angles = {std::atan2(head.x(), head.z()), std::asin(std::clamp(head.y(), -1.f, 1.f))};
    return true;
}

}  // namespace

Eigen::Vector3f gazeDirection(float yaw, float pitch) {
    return {std::sin(yaw) * std::cos(pitch), std::sin(pitch), std::cos(yaw) * std::cos(pitch)};
}

Eigen::Vector3f rotationCentre(const EyeballGeometry& eye, const Vec3& meshCentre) {
    const Eigen::Vector3f axis = Eigen::Vector3f(eye.optical_axis.x, eye.optical_axis.y, eye.optical_axis.z).normalized();
    const float plane = std::sqrt(std::max(0.f, eye.radius_mm * eye.radius_mm - eye.iris_radius_mm * eye.iris_radius_mm));
    return Eigen::Vector3f(meshCentre.x, meshCentre.y, meshCentre.z) + (plane - kIrisDistanceMm) * axis;
}

float eyeballRadiusMm() { return std::sqrt(kIrisDistanceMm * kIrisDistanceMm + kIrisRadiusMm * kIrisRadiusMm); }

Eigen::Vector2f irisCentreInImage(const Eigen::Vector3f& centre, const Eigen::Matrix3f& R, const fit::Camera& camera,
                                  const Eigen::Vector2f& angles) {
    return project(camera, centre + kIrisDistanceMm * (R * gazeDirection(angles.x(), angles.y())));
}

bool projectIris(const EyeObservation& eye, const Eigen::Matrix3f& R, const fit::Camera& camera, const Eigen::Vector2f& angles,
                 ProjectedIris& out) {
    const Eigen::Vector3f d = R * gazeDirection(angles.x(), angles.y());
    const Eigen::Vector3f c = eye.centre + kIrisDistanceMm * d;
    Eigen::Vector3f u = d.cross(Eigen::Vector3f::UnitY());
    if (u.norm() < 1e-3f) u = d.cross(Eigen::Vector3f::UnitX());
    u.normalize();
    const Eigen::Vector3f v = d.cross(u);
    if (c.z() <= 1.f || (c + kIrisRadiusMm * u).z() <= 1.f || (c + kIrisRadiusMm * v).z() <= 1.f) return false;
    out.centre = toPatch(*eye.patch, project(camera, c));
    out.axis1 = toPatch(*eye.patch, project(camera, c + kIrisRadiusMm * u)) - out.centre;
    out.axis2 = toPatch(*eye.patch, project(camera, c + kIrisRadiusMm * v)) - out.centre;
    return true;
}

GazeAngles fitGaze(const std::array<EyeObservation, 2>& eyes, const Eigen::Matrix3f& R, const fit::Camera& camera,
                   const GazeAngles& previous, bool havePrevious, const GazeFitSettings& s) {
    // Both eyes closed: nothing to see, the gaze holds (the priors alone would drift it towards ahead).
    if (havePrevious && eyes[0].weight <= 0.f && eyes[1].weight <= 0.f) return previous;
    GazeAngles a = havePrevious ? previous : GazeAngles{Eigen::Vector2f::Zero(), Eigen::Vector2f::Zero()};
    std::array<bool, 2> guessed{false, false};
    for (int e = 0; e < 2; ++e) {
        if (eyes[e].weight > 0.f) guessed[e] = centroidGuess(eyes[e], R, camera, a[e]);
    }
    // An eye with nothing to see starts where the other one looks.
    for (int e = 0; e < 2; ++e) {
        if (!guessed[e] && guessed[1 - e]) a[e] = a[1 - e];
    }
    // Per thread and sized once: a tracked frame allocates nothing here.
    thread_local Eigen::VectorXf r0(kResiduals), r1(kResiduals);
    thread_local Eigen::MatrixXf J(kResiduals, 4);
    constexpr float h = 0.25f * kDeg;
    std::array<float, 2> scale;
    for (int e = 0; e < 2; ++e) scale[e] = std::sqrt(eyes[e].weight) / s.data_sigma;
    for (int it = 0; it < s.iterations; ++it) {
        for (int e = 0; e < 2; ++e) dataResiduals(eyes[e], R, camera, a[e], scale[e], r0.data() + e * kDataResiduals);
        priorResiduals(a, previous, havePrevious, s, r0.data() + 2 * kDataResiduals);
        // A parameter of one eye moves only that eye's data residuals (and the priors).
        for (int k = 0; k < 4; ++k) {
            const int e = k / 2;
            GazeAngles b = a;
            b[e][k % 2] += h;
            r1 = r0;
            dataResiduals(eyes[e], R, camera, b[e], scale[e], r1.data() + e * kDataResiduals);
            priorResiduals(b, previous, havePrevious, s, r1.data() + 2 * kDataResiduals);
            J.col(k) = (r1 - r0) / h;
        }
        const Eigen::Matrix4f H = J.transpose() * J + 1e-4f * Eigen::Matrix4f::Identity();
        const Eigen::Vector4f step = -H.ldlt().solve(J.transpose() * r0);
        if (!step.allFinite()) break;
        // At most 10 degrees a step: the soft disc is only locally quadratic.
        const float largest = step.cwiseAbs().maxCoeff();
        const float limit = 10.f * kDeg;
        const Eigen::Vector4f taken = largest > limit ? Eigen::Vector4f(step * (limit / largest)) : step;
        for (int k = 0; k < 4; ++k) a[k / 2][k % 2] += taken[k];
        if (largest < 0.02f * kDeg) break;
    }
    for (auto& e : a) {
        e.x() = std::clamp(e.x(), -60.f * kDeg, 60.f * kDeg);
        e.y() = std::clamp(e.y(), -50.f * kDeg, 50.f * kDeg);
    }
    return a;
}

}  // namespace facetrack::gaze
