#pragma once
// Head and eye rotations as avatar apps want them. A tracker sees the head in
// the camera frame; an avatar wants the rotation away from looking straight
// into the camera, in its own axes. Frames (result.hpp has the tracker's):
//   rest frame  the face model's frame of a face looking straight into the
//               camera: x the subject's left, y up, z out of the face towards
//               the camera (right-handed; ARKit's face-anchor axes).
//   Unity frame the avatar's: +x its right, +y up, +z its forward
//               (left-handed), i.e. the rest frame with x negated.
// The avatar mirrors the user: turn your head to your left and the avatar
// turns to its own left.

#include "facetrack/result.hpp"

namespace facetrack::send {

/// R_rest = R_frontal^T R, the head's rotation from the frontal pose, in the
/// rest frame (R: camera_from_model, R_frontal = diag(1, -1, -1)).
Quaternion headFromRest(const HeadPose& pose);

/// The same rotation in Unity's frame: reflecting x maps (w, x, y, z) to (w, x, -y, -z).
Quaternion toUnity(const Quaternion& rest);

/// An eye's rotation from looking along the head's +z to looking along its
/// gaze, in the head's own (model) frame: the local rotation of an eye bone.
/// Identity when the gaze direction is not usable.
Quaternion eyeFromRest(const HeadPose& pose, const EyeGaze& eye);

/// q^s: the same axis, s times the angle (s in [0, 1] splits a rotation between bones).
Quaternion fraction(const Quaternion& q, float s);

/// q1 q2.
Quaternion multiply(const Quaternion& a, const Quaternion& b);

/// Intrinsic x-y-z Euler angles in degrees (R = Rx Ry Rz) of a rest-frame
/// rotation, by the right-hand rule: x > 0 looks down, y > 0 turns to the
/// subject's left, z > 0 tilts the head towards the subject's right shoulder.
Vec3 eulerXyzDeg(const Quaternion& rest);

}  // namespace facetrack::send
