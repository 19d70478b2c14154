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
/// The appearance term runs on every patch pixel of the classified region.
constexpr int kPixelsW = kClassifiedRegion.x1 - kClassifiedRegion.x0;
constexpr int kPixelsH = kClassifiedRegion.y1 - kClassifiedRegion.y0;
constexpr int kPixelResiduals = kPixelsW * kPixelsH;
constexpr int kEyeResiduals = kDataResiduals + kPixelResiduals;
constexpr int kPriorResiduals = 2 + 4 + 4;  // binocular 2, temporal 4, ahead 4
constexpr int kResiduals = 2 * kEyeResiduals + kPriorResiduals;

Eigen::Vector2f toPatch(const EyePatch& p, const Eigen::Vector2f& image) {
    const cv::Matx23f& a = p.patch_from_image;
    return {a(0, 0) * image.x() + a(0, 1) * image.y() + a(0, 2), a(1, 0) * image.x() + a(1, 1) * image.y() + a(1, 2)};
}

Eigen::Vector2f project(const core::Camera& c, const Eigen::Vector3f& p) {
    return {static_cast<float>(c.fx) * p.x() / p.z() + static_cast<float>(c.cx),
            static_cast<float>(c.fy) * p.y() / p.z() + static_cast<float>(c.cy)};
}

/// The projected iris as a soft indicator, 1 inside the ellipse and 0
/// outside, falling over about 0.7 patch pixels whatever the iris size:
///   D(q) = sigmoid(s (1 - |A (q - c)|)),  A = [a1 a2]^-1,
/// and its derivatives with respect to the eye's yaw and pitch, from those of
/// the centre c and of A (dA = -A dM A, M = [a1 a2]); the sharpness s is
/// held constant in them.
class SoftDisc {
public:
    /// The disc of `iris`; `moved[k]` is the disc at the angles plus h along
    /// angle k (yaw, pitch), whose differences give the derivatives.
    bool set(const ProjectedIris& iris, const std::array<ProjectedIris, 2>& moved, float h) {
        Eigen::Matrix2f axes;
        axes << iris.axis1, iris.axis2;
        if (!(std::fabs(axes.determinant()) > 1e-6f)) return false;
        inverse_ = axes.inverse();
        centre_ = iris.centre;
        sharpness_ = 0.5f * (iris.axis1.norm() + iris.axis2.norm()) / 0.7f;
        for (std::size_t k = 0; k < 2; ++k) {
            Eigen::Matrix2f movedAxes;
            movedAxes << moved[k].axis1, moved[k].axis2;
            dInverse_[k] = -inverse_ * ((movedAxes - axes) / h) * inverse_;
            dCentre_[k] = (moved[k].centre - iris.centre) / h;
        }
        return inverse_.allFinite() && centre_.allFinite();
    }
    /// D along row y from column x0 on, `step` patch pixels apart, into
    /// d[0, n), and dD/dyaw, dD/dpitch into dYaw, dPitch.
    void row(float x0, float y, int n, int step, float* d, float* dYaw, float* dPitch) const {
        const Eigen::Vector2f q = Eigen::Vector2f(x0, y) - centre_;
        Eigen::Vector2f v = inverse_ * q;
        std::array<Eigen::Vector2f, 2> dv;
        for (std::size_t k = 0; k < 2; ++k) dv[k] = dInverse_[k] * q - inverse_ * dCentre_[k];
        const float s = static_cast<float>(step);
        const Eigen::Vector2f dx = s * inverse_.col(0);
        const std::array<Eigen::Vector2f, 2> ddx = {s * dInverse_[0].col(0), s * dInverse_[1].col(0)};
        for (int i = 0; i < n; ++i, v += dx, dv[0] += ddx[0], dv[1] += ddx[1]) {
            const float rho = v.norm();
            const float t = sharpness_ * (1.f - rho);
            // Saturated far from the edge: exp only where the indicator is between 0 and 1.
            if (t > 12.f || t < -12.f) {
                d[i] = t > 0.f ? 1.f : 0.f;
                dYaw[i] = dPitch[i] = 0.f;
                continue;
            }
            d[i] = 1.f / (1.f + std::exp(-t));
            const float slope = -d[i] * (1.f - d[i]) * sharpness_ / std::max(rho, 1e-6f);
            dYaw[i] = slope * v.dot(dv[0]);
            dPitch[i] = slope * v.dot(dv[1]);
        }
    }
    /// The ellipse's bounding box half-sizes.
    Eigen::Vector2f reach() const {
        const Eigen::Matrix2f axes = inverse_.inverse();
        return {axes.row(0).norm(), axes.row(1).norm()};
    }
    const Eigen::Vector2f& centre() const { return centre_; }

private:
    Eigen::Matrix2f inverse_;
    Eigen::Vector2f centre_;
    float sharpness_ = 1.f;
    std::array<Eigen::Matrix2f, 2> dInverse_;
    std::array<Eigen::Vector2f, 2> dCentre_;
};

/// The disc of `eye` at `angles`, with its derivatives. False when the iris
/// is behind the camera or degenerate.
bool discAt(const EyeObservation& eye, const Eigen::Matrix3f& R, const core::Camera& camera, const Eigen::Vector2f& angles,
            SoftDisc& disc) {
    constexpr float h = 0.25f * kDeg;
    ProjectedIris iris;
    std::array<ProjectedIris, 2> moved;
    return projectIris(eye, R, camera, angles, iris) && projectIris(eye, R, camera, angles + Eigen::Vector2f(h, 0.f), moved[0]) &&
           projectIris(eye, R, camera, angles + Eigen::Vector2f(0.f, h), moved[1]) && disc.set(iris, moved, h);
}

/// Iris radii of sclera around the iris's box (plus 1.5 px) in the appearance
/// term's window: the start may be half an iris off, and the window must still
/// hold the whole iris (a margin of 0.6 radii doubled the synthetic error).
constexpr float kWindowMargin = 1.5f;

/// The patch pixels (region indices, half-open) the appearance term looks at
/// in one Gauss-Newton step: the iris's box with a margin of sclera around it.
struct PixelWindow {
    int x0 = 0, x1 = 0, y0 = 0, y1 = 0;
};

/// One eye's patch pixels over the classified region and how open the eye is
/// at each (P_open bilinear between the classifier's grid cells), gathered
/// once per fit.
struct EyePixels {
    std::array<float, kPixelResiduals> intensity, open;
    void gather(const EyeObservation& eye) {
        const PatchRegion r = kClassifiedRegion;
        for (int y = 0; y < kPixelsH; ++y) {
            const float gy = std::min(static_cast<float>(y) / r.step, static_cast<float>(kRegionH - 1));
            const int j = std::min(static_cast<int>(gy), kRegionH - 2);
            const float fy = gy - static_cast<float>(j);
            const float* row = eye.patch->pixels.ptr<float>(r.y0 + y);
            for (int x = 0; x < kPixelsW; ++x) {
                const float gx = std::min(static_cast<float>(x) / r.step, static_cast<float>(kRegionW - 1));
                const int i = std::min(static_cast<int>(gx), kRegionW - 2);
                const float fx = gx - static_cast<float>(i);
                const cv::Mat& o = *eye.open;
                const float top = (1.f - fx) * o.at<float>(j, i) + fx * o.at<float>(j, i + 1);
                const float bottom = (1.f - fx) * o.at<float>(j + 1, i) + fx * o.at<float>(j + 1, i + 1);
                const int k = y * kPixelsW + x;
                open[static_cast<std::size_t>(k)] = std::clamp((1.f - fy) * top + fy * bottom, 0.f, 1.f);
                intensity[static_cast<std::size_t>(k)] = row[r.x0 + x];
            }
        }
    }
};

/// The window around the disc: its box and a margin of sclera.
PixelWindow windowAround(const SoftDisc& disc) {
    PixelWindow w;
    const Eigen::Vector2f reach = disc.reach();
    if (!reach.allFinite()) return w;
    const Eigen::Vector2f margin = kWindowMargin * reach + Eigen::Vector2f::Constant(1.5f);
    const Eigen::Vector2f lo = disc.centre() - margin, hi = disc.centre() + margin;
    const auto clampTo = [](float v, int n) { return std::clamp(static_cast<int>(std::lround(v)), 0, n); };
    w.x0 = clampTo(lo.x() - static_cast<float>(kClassifiedRegion.x0), kPixelsW);
    w.x1 = clampTo(hi.x() - static_cast<float>(kClassifiedRegion.x0) + 1.f, kPixelsW);
    w.y0 = clampTo(lo.y() - static_cast<float>(kClassifiedRegion.y0), kPixelsH);
    w.y1 = clampTo(hi.y() - static_cast<float>(kClassifiedRegion.y0) + 1.f, kPixelsH);
    return w;
}

/// Residuals of one eye into r[0, kEyeResiduals) for the iris `disc` (null:
/// none seen, all 0), the classifier's maps then the pixels of the window about
/// it, and their derivatives with respect to the eye's yaw
/// and pitch into jYaw and jPitch (the same rows). The appearance term's tones
/// are held at their fit for this disc in the derivatives (a variable
/// projection's usual simplification: the residuals are exact, so is the minimum).
void eyeResiduals(const EyeObservation& eye, const EyePixels& pixels, const SoftDisc* seen, float mapScale, float pixelScale, float* r,
                  float* jYaw, float* jPitch) {
    std::fill(r, r + kEyeResiduals, 0.f);
    std::fill(jYaw, jYaw + kEyeResiduals, 0.f);
    std::fill(jPitch, jPitch + kEyeResiduals, 0.f);
    if (!seen) return;
    const SoftDisc& disc = *seen;
    for (int y = 0; y < kRegionH; ++y) {
        const float* pi = eye.iris->ptr<float>(y);
        const float* po = eye.open->ptr<float>(y);
        const int k = y * kRegionW;
        disc.row(static_cast<float>(kClassifiedRegion.x0), static_cast<float>(kClassifiedRegion.y(y)), kRegionW, kClassifiedRegion.step,
                 r + k, jYaw + k, jPitch + k);
        for (int x = 0; x < kRegionW; ++x) {
            r[k + x] = mapScale * (pi[x] - r[k + x] * po[x]);
            jYaw[k + x] *= -mapScale * po[x];
            jPitch[k + x] *= -mapScale * po[x];
        }
    }
    if (pixelScale <= 0.f) return;
    const PixelWindow window = windowAround(disc);
    if (window.x1 <= window.x0 || window.y1 <= window.y0) return;
    // The visible eye in two tones: the iris, uniform, inside the disc; the
    // sclera outside, a plane (a shaded eyeball is brighter on the light's
    // side). The tones are the open-weighted least-squares fit for this disc
    // (a region term with the disc as its shape; w = P_open^2 keeps the lids out).
    float* q = r + kDataResiduals;
    float* qYaw = jYaw + kDataResiduals;
    float* qPitch = jPitch + kDataResiduals;
    // The basis at a pixel: f = (D, 1 - D, (1 - D) X, (1 - D) Y), X and Y the pixel's column and
    // row about the region's centre over its size. Summed in scalars: f f^T has 10 distinct entries.
    static const std::array<float, kPixelsW> columnX = [] {
        std::array<float, kPixelsW> across{};
        for (int x = 0; x < kPixelsW; ++x) across[static_cast<std::size_t>(x)] = static_cast<float>(x - kPixelsW / 2) / kPixelsW;
        return across;
    }();
    const auto down = [](int y) { return static_cast<float>(y - kPixelsH / 2) / kPixelsH; };
    float nDD = 0.f, nDO = 0.f, nDX = 0.f, nDY = 0.f, nOO = 0.f, nOX = 0.f, nOY = 0.f, nXX = 0.f, nXY = 0.f, nYY = 0.f;
    float mD = 0.f, mO = 0.f, mX = 0.f, mY = 0.f;
    const int n = window.x1 - window.x0;
    for (int y = window.y0; y < window.y1; ++y) {
        const int k0 = y * kPixelsW + window.x0;
        disc.row(static_cast<float>(kClassifiedRegion.x0 + window.x0), static_cast<float>(kClassifiedRegion.y0 + y), n, 1, q + k0,
                 qYaw + k0, qPitch + k0);
        const float rowY = down(y);
        for (int x = window.x0; x < window.x1; ++x) {
            const int k = y * kPixelsW + x;
            const float o = pixels.open[static_cast<std::size_t>(k)];
            if (o < 0.02f) continue;  // the lids: no weight
            const float w = o * o, d = q[k], out = 1.f - d;
            const float fX = out * columnX[static_cast<std::size_t>(x)], fY = out * rowY;
            const float wd = w * d, wo = w * out, wX = w * fX, wY = w * fY;
            nDD += wd * d, nDO += wd * out, nDX += wd * fX, nDY += wd * fY;
            nOO += wo * out, nOX += wo * fX, nOY += wo * fY;
            nXX += wX * fX, nXY += wX * fY, nYY += wY * fY;
            const float intensity = pixels.intensity[static_cast<std::size_t>(k)];
            mD += wd * intensity, mO += wo * intensity, mX += wX * intensity, mY += wY * intensity;
        }
    }
    Eigen::Matrix4f normal;
    normal << nDD, nDO, nDX, nDY,  //
        nDO, nOO, nOX, nOY,        //
        nDX, nOX, nXX, nXY,        //
        nDY, nOY, nXY, nYY;
    const Eigen::Vector4f moment(mD, mO, mX, mY);
    const Eigen::Vector4f tones = (normal + 1e-3f * Eigen::Matrix4f::Identity()).ldlt().solve(moment);
    for (int y = window.y0; y < window.y1; ++y) {
        // m = mu D + (1 - D) plane: dm/dD = mu - plane.
        const float rowPlane = tones[1] + tones[3] * down(y);
        for (int x = window.x0; x < window.x1; ++x) {
            const int k = y * kPixelsW + x;
            const float o = pixels.open[static_cast<std::size_t>(k)];
            const float sclera = rowPlane + tones[2] * columnX[static_cast<std::size_t>(x)];
            const float contrast = tones[0] - sclera;
            q[k] = pixelScale * o * (pixels.intensity[static_cast<std::size_t>(k)] - (sclera + q[k] * contrast));
            qYaw[k] *= -pixelScale * o * contrast;
            qPitch[k] *= -pixelScale * o * contrast;
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

/// The priors' derivatives with respect to (yaw_L, pitch_L, yaw_R, pitch_R): constant.
template <class Rows>
void priorJacobian(bool havePrevious, const GazeFitSettings& s, Rows&& j) {
    j.setZero();
    j(0, 1) = 1.f / (s.pitch_sigma_deg * kDeg), j(0, 3) = -1.f / (s.pitch_sigma_deg * kDeg);
    j(1, 2) = 1.f / (s.vergence_sigma_deg * kDeg), j(1, 0) = -1.f / (s.vergence_sigma_deg * kDeg);
    for (int k = 0; k < 4; ++k) {
        j(2 + k, k) = havePrevious ? 1.f / (s.temporal_sigma_deg * kDeg) : 0.f;
        j(6 + k, k) = 1.f / (s.ahead_sigma_deg * kDeg);
    }
}

/// The iris probability's centroid back-projected onto the iris sphere: a
/// starting point that follows saccades without lag. False when there is too
/// little visible iris.
bool centroidGuess(const EyeObservation& eye, const Eigen::Matrix3f& R, const core::Camera& camera, Eigen::Vector2f& angles) {
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

Eigen::Vector2f irisCentreInImage(const Eigen::Vector3f& centre, const Eigen::Matrix3f& R, const core::Camera& camera,
                                  const Eigen::Vector2f& angles) {
    return project(camera, centre + kIrisDistanceMm * (R * gazeDirection(angles.x(), angles.y())));
}

bool projectIris(const EyeObservation& eye, const Eigen::Matrix3f& R, const core::Camera& camera, const Eigen::Vector2f& angles,
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

GazeAngles fitGaze(const std::array<EyeObservation, 2>& eyes, const Eigen::Matrix3f& R, const core::Camera& camera,
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
    thread_local Eigen::VectorXf r(kResiduals);
    thread_local Eigen::MatrixXf J(kResiduals, 4);
    thread_local std::array<EyePixels, 2> pixels;
    std::array<float, 2> mapScale, pixelScale;
    for (int e = 0; e < 2; ++e) {
        mapScale[e] = std::sqrt(eyes[e].weight) / s.data_sigma;
        pixelScale[e] = s.pixel_sigma > 0.f ? std::sqrt(eyes[e].weight) / s.pixel_sigma : 0.f;
        if (eyes[e].weight > 0.f) pixels[e].gather(eyes[e]);
    }
    // An eye's residuals depend on its own angles only: the other eye's columns stay 0 in its rows.
    J.setZero();
    priorJacobian(havePrevious, s, J.bottomRows(kPriorResiduals));
    for (int it = 0; it < s.iterations; ++it) {
        for (int e = 0; e < 2; ++e) {
            SoftDisc disc;
            const bool seen = mapScale[e] > 0.f && discAt(eyes[e], R, camera, a[e], disc);
            const int row = e * kEyeResiduals;
            eyeResiduals(eyes[e], pixels[e], seen ? &disc : nullptr, mapScale[e], pixelScale[e], r.data() + row, J.col(2 * e).data() + row,
                         J.col(2 * e + 1).data() + row);
        }
        priorResiduals(a, previous, havePrevious, s, r.data() + 2 * kEyeResiduals);
        // J^T J and J^T r by blocks: an eye's rows have only its own two columns.
        Eigen::Matrix4f H = J.bottomRows(kPriorResiduals).transpose() * J.bottomRows(kPriorResiduals) + 1e-4f * Eigen::Matrix4f::Identity();
        Eigen::Vector4f gradient = J.bottomRows(kPriorResiduals).transpose() * r.tail(kPriorResiduals);
        for (int e = 0; e < 2; ++e) {
            const float* residual = r.data() + e * kEyeResiduals;
            const float* yaw = J.col(2 * e).data() + e * kEyeResiduals;
            const float* pitch = J.col(2 * e + 1).data() + e * kEyeResiduals;
            // Eight partial sums of each (vectorised; one chain of additions would be latency-bound).
            std::array<float, 8> yy{}, yp{}, pp{}, yr{}, pr{};
            const auto add = [&](int k, std::size_t lane) {
                yy[lane] += yaw[k] * yaw[k], yp[lane] += yaw[k] * pitch[k], pp[lane] += pitch[k] * pitch[k];
                yr[lane] += yaw[k] * residual[k], pr[lane] += pitch[k] * residual[k];
            };
            constexpr int kWhole = kEyeResiduals / 8 * 8;
            for (int k = 0; k < kWhole; k += 8)
                for (std::size_t lane = 0; lane < 8; ++lane) add(k + static_cast<int>(lane), lane);
            for (int k = kWhole; k < kEyeResiduals; ++k) add(k, static_cast<std::size_t>(k - kWhole));
            const auto total = [](const std::array<float, 8>& a) {
                return ((a[0] + a[4]) + (a[1] + a[5])) + ((a[2] + a[6]) + (a[3] + a[7]));
            };
            H(2 * e, 2 * e) += total(yy), H(2 * e, 2 * e + 1) += total(yp), H(2 * e + 1, 2 * e) += total(yp);
            H(2 * e + 1, 2 * e + 1) += total(pp);
            gradient(2 * e) += total(yr), gradient(2 * e + 1) += total(pr);
        }
        const Eigen::Vector4f step = -H.ldlt().solve(gradient);
        if (!step.allFinite()) break;
        // At most 10 degrees a step: the soft disc is only locally quadratic.
        const float largest = step.cwiseAbs().maxCoeff();
        const float limit = 10.f * kDeg;
        const Eigen::Vector4f taken = largest > limit ? Eigen::Vector4f(step * (limit / largest)) : step;
        for (int k = 0; k < 4; ++k) a[k / 2][k % 2] += taken[k];
        if (largest < s.converged_step_deg * kDeg) break;
    }
    for (auto& e : a) {
        e.x() = std::clamp(e.x(), -60.f * kDeg, 60.f * kDeg);
        e.y() = std::clamp(e.y(), -50.f * kDeg, 50.f * kDeg);
    }
    return a;
}

}  // namespace facetrack::gaze
