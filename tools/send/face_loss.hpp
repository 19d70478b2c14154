#pragma once
// What an avatar is sent while the face comes and goes. Frozen on its last
// expression when the face leaves, an avatar looks broken; so once the face is
// lost it relaxes: from where it was to rest (no expression, the head and eyes
// straight at the camera where the head last was, eyes open) over
// kFaceLossEaseSeconds, then holds. When a face is found again the avatar
// eases from wherever it is to the tracked face over the same time. The ease
// is a smoothstep, s^2 (3 - 2 s) with s the share of the time gone.

#include "facetrack/result.hpp"

namespace facetrack::send {

constexpr double kFaceLossEaseSeconds = 0.5;

/// The mix (1 - t) a + t b of two faces' expression, pose and gaze (rotations
/// by slerp, directions renormalised) into `out`; landmarks, box and the
/// rest are b's. A field only one of them has is b's.
void blendFaces(const FaceResult& a, const FaceResult& b, float t, FaceResult& out);

/// `face` at rest: expression 0, the head turned straight at the camera at the
/// same place, eyes open and looking straight out of the face.
FaceResult restingFace(const FaceResult& face);

class FaceLossEasing {
public:
    /// The face to send for `frame` (its first face) at `time_s`: eased as the
    /// file comment says. Null until a face was first seen.
    const FaceResult* update(const FrameResult& frame, double time_s);
    /// Whether the last frame had a face.
    bool tracking() const { return tracking_; }

private:
    FaceResult from_;        ///< where the avatar was when the current ease began
    FaceResult rest_;        ///< where a lost face eases to
    FaceResult out_;         ///< what is sent
    double since_ = 0.0;     ///< when the current ease began
    bool seen_ = false;      ///< a face was seen at least once
    bool tracking_ = false;  ///< the last frame had a face
};

}  // namespace facetrack::send
