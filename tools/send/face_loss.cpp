#include "send/face_loss.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace facetrack::send {

namespace {

float mix(float a, float b, float t) { return a + t * (b - a); }
Vec3 mix(const Vec3& a, const Vec3& b, float t) { return {mix(a.x, b.x, t), mix(a.y, b.y, t), mix(a.z, b.z, t)}; }

Vec3 normalised(const Vec3& v) {
    const float n = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    return n > 1e-6f ? Vec3{v.x / n, v.y / n, v.z / n} : v;
}

Eigen::Quaternionf eigen(const Quaternion& q) { return Eigen::Quaternionf(q.w, q.x, q.y, q.z).normalized(); }

/// R and t into the pose's two matrices (column-major; result.hpp).
void fillMatrices(HeadPose& pose) {
    const Eigen::Matrix3f r = eigen(pose.rotation).toRotationMatrix();
    const float t[3] = {pose.translation_mm.x, pose.translation_mm.y, pose.translation_mm.z};
    pose.camera_from_model.fill(0.f);
    for (int c = 0; c < 3; ++c)
        for (int row = 0; row < 3; ++row) pose.camera_from_model[static_cast<std::size_t>(4 * c + row)] = r(row, c);
    for (int row = 0; row < 3; ++row) pose.camera_from_model[static_cast<std::size_t>(12 + row)] = t[row];
    pose.camera_from_model[15] = 1.f;
    pose.gl_model_view = pose.camera_from_model;
    for (int c = 0; c < 4; ++c) {  // diag(1, -1, -1, 1) M: rows y and z negated
        pose.gl_model_view[static_cast<std::size_t>(4 * c + 1)] *= -1.f;
        pose.gl_model_view[static_cast<std::size_t>(4 * c + 2)] *= -1.f;
    }
}

void blendEye(const EyeGaze& a, const EyeGaze& b, float t, EyeGaze& out) {
    out = b;
    out.direction = normalised(mix(a.direction, b.direction, t));
    out.direction_head = normalised(mix(a.direction_head, b.direction_head, t));
    out.yaw_deg = mix(a.yaw_deg, b.yaw_deg, t);
    out.pitch_deg = mix(a.pitch_deg, b.pitch_deg, t);
    out.openness = mix(a.openness, b.openness, t);
}

}  // namespace

void blendFaces(const FaceResult& a, const FaceResult& b, float t, FaceResult& out) {
    out = b;
    if (a.expression && b.expression) {
        for (std::size_t k = 0; k < out.expression->arkit.size(); ++k)
            out.expression->arkit[k] = mix(a.expression->arkit[k], b.expression->arkit[k], t);
        if (a.expression->native.size() == b.expression->native.size()) {
            for (std::size_t k = 0; k < out.expression->native.size(); ++k)
                out.expression->native[k] = mix(a.expression->native[k], b.expression->native[k], t);
        }
    }
    if (a.pose && b.pose) {
        const Eigen::Quaternionf q = eigen(a.pose->rotation).slerp(t, eigen(b.pose->rotation));
        out.pose->rotation = {q.w(), q.x(), q.y(), q.z()};
        out.pose->euler_deg = mix(a.pose->euler_deg, b.pose->euler_deg, t);
        out.pose->translation_mm = mix(a.pose->translation_mm, b.pose->translation_mm, t);
        fillMatrices(*out.pose);
    }
    if (a.gaze && b.gaze) {
        blendEye(a.gaze->left, b.gaze->left, t, out.gaze->left);
        blendEye(a.gaze->right, b.gaze->right, t, out.gaze->right);
    }
}

FaceResult restingFace(const FaceResult& face) {
    FaceResult rest = face;
    if (rest.expression) {
        rest.expression->arkit.fill(0.f);
        std::fill(rest.expression->native.begin(), rest.expression->native.end(), 0.f);
    }
    if (rest.pose) {
        rest.pose->rotation = {0.f, 1.f, 0.f, 0.f};  // a half turn about x: facing the camera (result.hpp)
        rest.pose->euler_deg = {0.f, 0.f, 0.f};
        fillMatrices(*rest.pose);
    }
    if (rest.gaze) {
        for (EyeGaze* eye : {&rest.gaze->left, &rest.gaze->right}) {
            eye->direction = {0.f, 0.f, -1.f};  // out of a face that faces the camera
            eye->direction_head = {0.f, 0.f, 1.f};
            eye->yaw_deg = eye->pitch_deg = 0.f;
            eye->openness = 1.f;
        }
    }
    return rest;
}

const FaceResult* FaceLossEasing::update(const FrameResult& frame, double time_s) {
    const bool face = !frame.faces.empty();
    if (face && !seen_) {  // the first face: nothing to ease from
        seen_ = true;
        from_ = frame.faces.front();
        since_ = time_s - kFaceLossEaseSeconds;
    } else if (face != tracking_ && seen_) {  // found or lost: ease from where the avatar is
        from_ = out_;
        since_ = time_s;
        if (!face) rest_ = restingFace(out_);
    }
    tracking_ = face;
    if (!seen_) return nullptr;
    const double s = std::clamp((time_s - since_) / kFaceLossEaseSeconds, 0.0, 1.0);
    const auto t = static_cast<float>(s * s * (3.0 - 2.0 * s));
    const FaceResult& to = face ? frame.faces.front() : rest_;
    if (t < 1.f) {
        blendFaces(from_, to, t, out_);
    } else {
        out_ = to;
    }
    return &out_;
}

}  // namespace facetrack::send
