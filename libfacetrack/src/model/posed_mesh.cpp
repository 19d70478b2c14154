#include "facetrack/posed_mesh.hpp"

#include "facetrack/error.hpp"

#include <cmath>

namespace facetrack {

namespace {

Vec3 cross(const Vec3& a, const Vec3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
float dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3 operator+(const Vec3& a, const Vec3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec3 operator-(const Vec3& a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3 operator*(float s, const Vec3& a) { return {s * a.x, s * a.y, s * a.z}; }

Vec3 vertexMean(const std::vector<Vec3>& mesh, int first, int last) {
    Vec3 sum;
    for (int i = first; i <= last; ++i) sum = sum + mesh[i];
    return (1.f / static_cast<float>(last - first + 1)) * sum;
}

}  // namespace

Vec3 rotate(const Quaternion& q, const Vec3& v) {
    // v + 2 u x (u x v + w v), u the vector part.
    const Vec3 u{q.x, q.y, q.z};
    const Vec3 t = cross(u, v) + q.w * v;
    return v + 2.f * cross(u, t);
}

Vec3 rotateBack(const Quaternion& q, const Vec3& v) { return rotate({q.w, -q.x, -q.y, -q.z}, v); }

Vec3 toCamera(const HeadPose& pose, const Vec3& modelPoint) { return rotate(pose.rotation, modelPoint) + pose.translation_mm; }

EyeRig::EyeRig(const FaceModel& model, const EyeballGeometry& eye) : eye_(eye) {
    rest_mean_ = vertexMean(model.vertices({}, {}), eye.first_vertex, eye.last_vertex);
}

std::array<EyeRig, 2> EyeRig::both(const FaceModel& model) {
    return {EyeRig(model, model.leftEyeball()), EyeRig(model, model.rightEyeball())};
}

Vec3 EyeRig::centre(const std::vector<Vec3>& mesh) const {
    return eye_.centre + (vertexMean(mesh, eye_.first_vertex, eye_.last_vertex) - rest_mean_);
}

void EyeRig::turn(std::vector<Vec3>& mesh, const Vec3& direction) const {
    const float length = std::sqrt(dot(direction, direction));
    if (!(length > 0.f) || !std::isfinite(length)) return;
    const Vec3 to = (1.f / length) * direction;
    const Vec3& from = eye_.optical_axis;
    // The shortest rotation from `from` to `to`, as a quaternion (half-angle form).
    const float c = dot(from, to);
    if (c < -0.999f) return;  // looking backwards through the head: not a gaze
    const Vec3 axis = cross(from, to);
    const float s = std::sqrt(2.f * (1.f + c));
    const Quaternion q{0.5f * s, axis.x / s, axis.y / s, axis.z / s};
    const Vec3 pivot = centre(mesh);
    for (int i = eye_.first_vertex; i <= eye_.last_vertex; ++i) mesh[i] = pivot + rotate(q, mesh[i] - pivot);
}

MeshPoser::MeshPoser(std::shared_ptr<const FaceModel> model)
    : model_(model ? std::move(model) : throw Error("MeshPoser: no face model")), eyes_(EyeRig::both(*model_)) {}

void MeshPoser::modelFrame(const FaceResult& face, std::vector<Vec3>& out) const {
    static const std::vector<float> neutral;
    model_->vertices(face.identity, face.expression ? face.expression->native : neutral, out);
    if (face.gaze && face.pose) {
        // Gaze is in the camera frame; the mesh is in the model frame.
        eyes_[0].turn(out, rotateBack(face.pose->rotation, face.gaze->left.direction));
        eyes_[1].turn(out, rotateBack(face.pose->rotation, face.gaze->right.direction));
    }
}

void MeshPoser::cameraFrame(const FaceResult& face, std::vector<Vec3>& out) const {
    if (!face.pose) throw Error("MeshPoser::cameraFrame: the face has no pose");
    modelFrame(face, out);
    for (Vec3& v : out) v = toCamera(*face.pose, v);
}

std::array<Vec3, 2> MeshPoser::eyeCentres(const std::vector<Vec3>& modelMesh) const {
    return {eyes_[0].centre(modelMesh), eyes_[1].centre(modelMesh)};
}

}  // namespace facetrack
