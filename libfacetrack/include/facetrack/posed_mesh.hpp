#pragma once
/// \file
/// Putting the face model's mesh where a FaceResult says the face is: the
/// face's identity and expression applied, the eyeballs turned by its gaze,
/// and the head moved by its pose. What an avatar or an overlay needs.
/// Millimetres throughout; frames as in result.hpp.
///
/// Thread-safety: EyeRig and MeshPoser are immutable after construction; one
/// instance may serve any number of threads.

#include "facetrack/face_model.hpp"
#include "facetrack/geometry.hpp"
#include "facetrack/result.hpp"

#include <array>
#include <memory>
#include <vector>

namespace facetrack {

/// q v q* (q a unit quaternion).
Vec3 rotate(const Quaternion& q, const Vec3& v);
/// q* v q: the inverse rotation.
Vec3 rotateBack(const Quaternion& q, const Vec3& v);
/// x_camera = R x_model + t, the head pose applied to a model-frame point.
Vec3 toCamera(const HeadPose& pose, const Vec3& modelPoint);

/// One eyeball of a model, ready to find its centre on any mesh and to turn it.
class EyeRig {
public:
    EyeRig(const FaceModel& model, const EyeballGeometry& eye);
    /// Both eyes: the subject's left, then right.
    static std::array<EyeRig, 2> both(const FaceModel& model);

    /// The eyeball's rotation centre on `mesh` (a model-frame FaceModel::vertices
    /// of any identity and expression): the rest centre moved as the eyeball's vertices moved.
    Vec3 centre(const std::vector<Vec3>& mesh) const;
    /// Turns the eyeball's vertices of `mesh` about centre() so that its
    /// optical axis points along `direction` (model frame, need not be unit).
    /// A zero, non-finite or backwards direction leaves the eye as it is.
    void turn(std::vector<Vec3>& mesh, const Vec3& direction) const;

private:
    EyeballGeometry eye_;
    Vec3 rest_mean_;  // mean of the eyeball's vertices on the mean face
};

/// Poses a model's mesh for a FaceResult.
class MeshPoser {
public:
    explicit MeshPoser(std::shared_ptr<const FaceModel> model);

    /// The face's mesh in the model frame: its identity and native expression
    /// applied (FaceModel::vertices; none: the mean, neutral face) and, when it
    /// has gaze and pose, each eyeball turned to look along its gaze. `out` is
    /// resized; its memory is reused.
    void modelFrame(const FaceResult& face, std::vector<Vec3>& out) const;
    /// The same mesh moved into the camera frame by face.pose. Throws Error
    /// when the face has no pose.
    void cameraFrame(const FaceResult& face, std::vector<Vec3>& out) const;
    /// The eyeball centres (subject's left, right) on a modelFrame() mesh.
    std::array<Vec3, 2> eyeCentres(const std::vector<Vec3>& modelMesh) const;

    const FaceModel& model() const { return *model_; }

private:
    std::shared_ptr<const FaceModel> model_;
    std::array<EyeRig, 2> eyes_;
};

}  // namespace facetrack
