#pragma once
// Helpers that put the face model's mesh where a FaceResult says it is:
// rotations by the head pose's quaternion, and the eyeballs turned by gaze.
// Shared by the 2D overlay and the demo's avatar.

#include "facetrack/face_model.hpp"
#include "facetrack/geometry.hpp"

#include <array>
#include <vector>

namespace facetrack::tools {

/// q v q* (q a unit quaternion).
Vec3 rotate(const Quaternion& q, const Vec3& v);
/// q* v q: the inverse rotation.
Vec3 rotateBack(const Quaternion& q, const Vec3& v);

/// One eyeball of a model, ready to find its centre on any mesh and to turn it.
class EyeRig {
public:
    EyeRig(const FaceModel& model, const EyeballGeometry& eye);
    /// Both eyes: the subject's left, then right.
    static std::array<EyeRig, 2> both(const FaceModel& model);

    /// The eyeball's rotation centre on `mesh` (FaceModel::vertices of any
    /// identity and expression): the rest centre moved as the eyeball's vertices moved.
    Vec3 centre(const std::vector<Vec3>& mesh) const;
    /// Turns the eyeball's vertices of `mesh` about centre() so that its
    /// optical axis points along `direction` (model frame, need not be unit).
    void turn(std::vector<Vec3>& mesh, const Vec3& direction) const;

private:
    EyeballGeometry eye_;
    Vec3 rest_mean_;  // mean of the eyeball's vertices on the mean face
};

}  // namespace facetrack::tools
