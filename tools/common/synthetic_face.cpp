#include "common/synthetic_face.hpp"

#include "gaze/gaze_fit.hpp"

#include "facetrack/error.hpp"
#include "facetrack/posed_mesh.hpp"

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace facetrack::tools {

namespace {
constexpr float kDeg = 3.14159265358979f / 180.f;

Eigen::Vector3f eig(const Vec3& v) { return {v.x, v.y, v.z}; }
Eigen::Matrix3f rotationOf(const Quaternion& q) { return Eigen::Quaternionf(q.w, q.x, q.y, q.z).normalized().toRotationMatrix(); }

/// Iris texture: radial streaks and a darker limbal ring; `radial` 0 centre .. 1 edge.
float irisShade(float radial, float angle) {
    if (radial < 0.42f) return 18.f;  // pupil
    const float streaks = 0.5f + 0.5f * std::sin(23.f * angle) * std::sin(7.f * angle + 3.f * radial);
    float shade = 70.f + 35.f * streaks * (1.f - radial);
    if (radial > 0.85f) shade *= 0.55f;  // limbal ring
    return shade;
}
}  // namespace

/// The skin's albedo at a point of the neutral mean face seen from the front
/// (model frame x, y in mm): the brows, a band from 1 mm above the landmark
/// convention's brow line (the line 300-W annotators trace along the brow's
/// upper edge) to 5 mm below it at the inner end and 3 mm at the outer; the
/// lips, inside the outer lip contour; skin elsewhere. A face without them is
/// not a face to a landmark regressor trained on photographs: its brow points,
/// and with them the head's pitch, were guesses (docs/gaze.md).
class FaceMarkings {
public:
    /// `points`: the neutral face's landmarks (FaceModel::landmarkPoints).
    explicit FaceMarkings(const std::vector<Vec3>& points) {
        for (std::size_t i = 0; i < points.size(); ++i) landmarks_[i] = {points[i].x, points[i].y};
        down_ = points[8].y > points[19].y ? 1.f : -1.f;
    }

    float albedo(const Eigen::Vector2f& p) const {
        for (const auto& [first, inner] : {std::array<int, 2>{17, 21}, std::array<int, 2>{22, 22}}) {
            float drop = 0.f, along = 0.f;
            if (belowBrow(p, first, inner, drop, along) && drop >= -1.f && drop <= 5.f - 2.f * along) return 0.42f;
        }
        return insideLip(p) ? 0.72f : 1.f;
    }

private:
    bool insideLip(const Eigen::Vector2f& p) const {
        bool in = false;
        for (std::size_t i = 48, j = 59; i < 60; j = i++) {
            const Eigen::Vector2f &a = landmarks_[i], &b = landmarks_[j];
            if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) in = !in;
        }
        return in;
    }
    /// How far p lies below a brow's line (mm, negative above it), and where
    /// along the brow (0 inner end .. 1 outer); false outside the brow's span.
    bool belowBrow(const Eigen::Vector2f& p, int first, int inner, float& drop, float& along) const {
        for (int i = first; i < first + 4; ++i) {
            const Eigen::Vector2f &a = landmarks_[static_cast<std::size_t>(i)], &b = landmarks_[static_cast<std::size_t>(i + 1)];
            const float s = (p.x() - a.x()) / (b.x() - a.x());
            if (!(s >= 0.f && s <= 1.f)) continue;
            drop = down_ * (p.y() - (a.y() + s * (b.y() - a.y())));
            along = std::fabs(static_cast<float>(i) + s - static_cast<float>(inner)) / 4.f;
            return true;
        }
        return false;
    }

    std::array<Eigen::Vector2f, 68> landmarks_;
    float down_ = 1.f;  // the sign of y from the brows towards the chin
};

SyntheticRenderer::SyntheticRenderer(std::shared_ptr<const FaceModel> model, bool markings) : model_(std::move(model)) {
    if (!model_) throw Error("SyntheticRenderer: no face model");
    const int face = model_->faceVertexCount();
    for (const auto& t : model_->triangles()) {
        if (t[0] < face && t[1] < face && t[2] < face) skin_.push_back(t);
    }
    landmark_vertices_ = model_->landmarkVertices();
    // Where each vertex sits on the neutral face seen from the front: the brows
    // and lips are painted there, per pixel. The sides of the head are plain skin.
    const std::vector<Vec3> neutral = model_->vertices({}, {});
    const std::vector<Vec3> points = model_->landmarkPoints(neutral);
    const float noseDepth = points[27].z;
    for (int v = 0; v < face; ++v) {
        const Vec3& p = neutral[static_cast<std::size_t>(v)];
        neutral_front_.push_back({p.x, p.y, std::fabs(p.z - noseDepth) <= 25.f ? 1.f : 0.f});
    }
    if (markings) markings_ = std::make_shared<const FaceMarkings>(points);
}

Vec3 SyntheticRenderer::gazeInCamera(const SyntheticFace& f, int e) const {
    const Eigen::Vector3f d = rotationOf(f.rotation) * gaze::gazeDirection(f.gaze_deg[static_cast<std::size_t>(e)][0] * kDeg,
                                                                           f.gaze_deg[static_cast<std::size_t>(e)][1] * kDeg);
    return {d.x(), d.y(), d.z()};
}

namespace {
Landmarks68 project(const SyntheticFace& f, const std::vector<Vec3>& points) {
    const Eigen::Matrix3f R = rotationOf(f.rotation);
    Landmarks68 out;
    for (std::size_t i = 0; i < out.size(); ++i) {
        const Eigen::Vector3f p = R * eig(points[i]) + eig(f.translation_mm);
        out[i] = {f.fx * p.x() / p.z() + f.cx, f.fy * p.y() / p.z() + f.cy};
    }
    return out;
}
}  // namespace

Landmarks68 SyntheticRenderer::landmarks(const SyntheticFace& f) const {
    return project(f, model_->landmarkPoints(model_->vertices({}, f.expression)));
}

Box SyntheticRenderer::faceBox(const SyntheticFace& f) const {
    // From the landmark vertices, not the convention's points: the box stands for a
    // detector's, which does not depend on where an annotator puts the brows.
    const std::vector<Vec3> mesh = model_->vertices({}, f.expression);
    std::vector<Vec3> vertices;
    for (const int v : landmark_vertices_) vertices.push_back(mesh[static_cast<std::size_t>(v)]);
    Box b{1e9f, 1e9f, -1e9f, -1e9f};
    for (const Point2& p : project(f, vertices)) b = {std::min(b.x0, p.x), std::min(b.y0, p.y), std::max(b.x1, p.x), std::max(b.y1, p.y)};
    const float pad = 0.1f * b.width();
    return {b.x0 - pad, b.y0 - 2 * pad, b.x1 + pad, b.y1 + pad};
}

float SyntheticRenderer::interocularPx(const SyntheticFace& f) const {
    const float iod = model_->leftEyeball().centre.x - model_->rightEyeball().centre.x;
    return f.fx * iod / f.translation_mm.z;
}

cv::Mat SyntheticRenderer::render(const SyntheticFace& f, ClassMap* classes) const {
    const std::vector<Vec3> mesh = model_->vertices({}, f.expression);
    const Eigen::Matrix3f R = rotationOf(f.rotation);
    const Eigen::Vector3f t = eig(f.translation_mm);
    const int n = model_->faceVertexCount();
    std::vector<Eigen::Vector3f> cam(static_cast<std::size_t>(n)), normal(static_cast<std::size_t>(n), Eigen::Vector3f::Zero());
    for (int i = 0; i < n; ++i) cam[static_cast<std::size_t>(i)] = R * eig(mesh[static_cast<std::size_t>(i)]) + t;
    for (const auto& tri : skin_) {
        const Eigen::Vector3f& a = cam[static_cast<std::size_t>(tri[0])];
        const Eigen::Vector3f nrm = (cam[static_cast<std::size_t>(tri[1])] - a).cross(cam[static_cast<std::size_t>(tri[2])] - a);
        for (const int v : tri) normal[static_cast<std::size_t>(v)] += nrm;
    }
    cv::Mat depth(f.height, f.width, CV_32F, cv::Scalar(1e9f));
    cv::Mat shade(f.height, f.width, CV_32F, cv::Scalar(40.f));  // background
    const Eigen::Vector3f light = Eigen::Vector3f(f.light[0], f.light[1], f.light[2]).normalized();
    for (const auto& tri : skin_) {
        std::array<Eigen::Vector2f, 3> p;
        std::array<float, 3> z, lit;
        std::array<Eigen::Vector3f, 3> front;
        bool behind = false;
        for (int k = 0; k < 3; ++k) {
            const Eigen::Vector3f& v = cam[static_cast<std::size_t>(tri[static_cast<std::size_t>(k)])];
            behind = behind || v.z() < 10.f;
            p[k] = {f.fx * v.x() / v.z() + f.cx, f.fy * v.y() / v.z() + f.cy};
            z[k] = v.z();
            const Eigen::Vector3f nn = normal[static_cast<std::size_t>(tri[static_cast<std::size_t>(k)])].normalized();
            lit[k] = 0.35f + 0.65f * std::fabs(nn.dot(light));  // either winding
            const auto& n = neutral_front_[static_cast<std::size_t>(tri[static_cast<std::size_t>(k)])];
            front[k] = {n[0], n[1], n[2]};
        }
        if (behind) continue;
        const float area = (p[1] - p[0]).x() * (p[2] - p[0]).y() - (p[1] - p[0]).y() * (p[2] - p[0]).x();
        if (std::fabs(area) < 1e-6f) continue;
        const int x0 = std::max(0, static_cast<int>(std::floor(std::min({p[0].x(), p[1].x(), p[2].x()}))));
        const int x1 = std::min(f.width - 1, static_cast<int>(std::ceil(std::max({p[0].x(), p[1].x(), p[2].x()}))));
        const int y0 = std::max(0, static_cast<int>(std::floor(std::min({p[0].y(), p[1].y(), p[2].y()}))));
        const int y1 = std::min(f.height - 1, static_cast<int>(std::ceil(std::max({p[0].y(), p[1].y(), p[2].y()}))));
        for (int y = y0; y <= y1; ++y) {
            for (int x = x0; x <= x1; ++x) {
                const Eigen::Vector2f q(static_cast<float>(x), static_cast<float>(y));
                const float w0 = ((p[1] - q).x() * (p[2] - q).y() - (p[1] - q).y() * (p[2] - q).x()) / area;
                const float w1 = ((p[2] - q).x() * (p[0] - q).y() - (p[2] - q).y() * (p[0] - q).x()) / area;
                const float w2 = 1.f - w0 - w1;
                if (w0 < 0.f || w1 < 0.f || w2 < 0.f) continue;
                const float zz = w0 * z[0] + w1 * z[1] + w2 * z[2];
                float& d = depth.at<float>(y, x);
                if (zz >= d) continue;
                d = zz;
                const Eigen::Vector3f at = w0 * front[0] + w1 * front[1] + w2 * front[2];
                const float albedo = markings_ && at.z() > 0.99f ? markings_->albedo(at.head<2>()) : 1.f;
                shade.at<float>(y, x) = 185.f * f.skin * albedo * (w0 * lit[0] + w1 * lit[1] + w2 * lit[2]);
            }
        }
    }
    // The eyeballs, ray-traced where they are nearer than the skin.
    const std::array<EyeballGeometry, 2> geometry = {model_->leftEyeball(), model_->rightEyeball()};
    const auto rigs = EyeRig::both(*model_);
    const float radius = gaze::eyeballRadiusMm();
    cv::Mat eyeball(f.height, f.width, CV_8U, cv::Scalar(0));
    cv::Mat kind(f.height, f.width, CV_8U, cv::Scalar(0));
    for (int e = 0; e < 2; ++e) {
        const Eigen::Vector3f centre = R * gaze::rotationCentre(geometry[static_cast<std::size_t>(e)],
                                                                rigs[static_cast<std::size_t>(e)].centre(mesh)) +
                                       t;
        const Eigen::Vector3f g = R * gaze::gazeDirection(f.gaze_deg[static_cast<std::size_t>(e)][0] * kDeg,
                                                          f.gaze_deg[static_cast<std::size_t>(e)][1] * kDeg);
        const Eigen::Vector3f u = g.cross(Eigen::Vector3f::UnitY()).normalized(), v = g.cross(u);
        const float reach = radius * f.fx / centre.z() + 2.f;
        const float px = f.fx * centre.x() / centre.z() + f.cx, py = f.fy * centre.y() / centre.z() + f.cy;
        for (int y = std::max(0, static_cast<int>(py - reach)); y <= std::min(f.height - 1, static_cast<int>(py + reach)); ++y) {
            for (int x = std::max(0, static_cast<int>(px - reach)); x <= std::min(f.width - 1, static_cast<int>(px + reach)); ++x) {
                const Eigen::Vector3f ray = Eigen::Vector3f((x - f.cx) / f.fx, (y - f.cy) / f.fy, 1.f).normalized();
                const float b = ray.dot(centre), c = centre.squaredNorm() - radius * radius, disc = b * b - c;
                if (disc < 0.f) continue;
                const float s = b - std::sqrt(disc);
                const Eigen::Vector3f hit = s * ray;
                if (hit.z() >= depth.at<float>(y, x)) continue;
                depth.at<float>(y, x) = hit.z();
                const Eigen::Vector3f local = hit - centre;
                const float along = local.dot(g);
                float value;
                if (along >= gaze::kIrisDistanceMm) {
                    const Eigen::Vector3f across = local - along * g;
                    const float radial = across.norm() / gaze::kIrisRadiusMm;
                    value = std::min(250.f, f.iris * irisShade(std::min(radial, 1.f), std::atan2(across.dot(v), across.dot(u))));
                    kind.at<std::uint8_t>(y, x) = 2;
                } else {
                    kind.at<std::uint8_t>(y, x) = 1;
                    value = 215.f * (0.75f + 0.25f * std::max(0.f, local.normalized().dot(light)));
                }
                shade.at<float>(y, x) = value;
                eyeball.at<std::uint8_t>(y, x) = 255;
            }
        }
    }
    // Lash lines: the skin bordering the visible eyeball darkens, as real lids do.
    cv::Mat rim;
    cv::dilate(eyeball, rim, cv::Mat(), cv::Point(-1, -1), std::max(1, static_cast<int>(std::lround(f.lash * interocularPx(f) / 60.f))));
    shade.setTo(cv::Scalar(std::clamp(90.f - 35.f * f.lash, 20.f, 120.f)), rim & ~eyeball);
    if (classes) *classes = kind;
    cv::Mat image;
    shade.convertTo(image, CV_8U);
    if (f.blur_sigma > 0.f) cv::GaussianBlur(image, image, cv::Size(), f.blur_sigma);
    cv::Mat noise(image.size(), CV_32F);
    std::mt19937 rng(f.seed);
    std::normal_distribution<float> gauss(0.f, f.noise_sigma);
    for (int y = 0; y < noise.rows; ++y)
        for (int x = 0; x < noise.cols; ++x) noise.at<float>(y, x) = gauss(rng);
    cv::Mat noisy;
    image.convertTo(noisy, CV_32F);
    noisy += noise;
    noisy.convertTo(image, CV_8U);
    // Skin-toned BGR: the trackers convert to grey anyway; the tint keeps the detector's input natural.
    cv::Mat bgr;
    cv::merge(std::vector<cv::Mat>{image * 0.85, image * 0.95, image}, bgr);
    return bgr;
}

}  // namespace facetrack::tools
