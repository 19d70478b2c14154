#pragma once
// The "gaze" stage (Wang, Shi, Xia, Chai 2016): per eye, the eye patch cut by
// the landmarks' corners, the pixel forest's iris and eye-opening maps, the
// aperture forest's lid opening; then both eyes' gaze as one MAP estimate
// (gaze_fit.hpp) with the eyeball model placed by the head pose.
//
// Openness: the aperture over this face's own open-eye aperture (a running
// 70th percentile, started at the model's), 0..1; each eye on its own, so a
// wink is a wink. A closing eye gives the fit no data: its gaze follows the
// other eye, or holds when both close, so a blink does not move the gaze. The
// open gap expected follows the gaze pitch as the face model's lids do
// (LidsFollowingGaze); an eye that reads partly closed is asked, by a probe
// fit, whether its iris went down with its lids (a look-down, not a blink).
//
// Reads: landmarks, pose, identity. Writes: gaze, and the ARKit eye shapes
// (native eyeBlink, eyeLook*, eyeWide of the face model, ARKit recomputed;
// its contract lists them as smoothed already: the filter leaves them as they
// are). Never loses the face.

#include "pipeline/stage.hpp"

#include "facetrack/eye_model.hpp"
#include "facetrack/face_model.hpp"

#include <array>
#include <memory>
#include <vector>

namespace facetrack::gaze {

/// `eyes` null: the stage is not available.
std::unique_ptr<pipeline::Stage> makeGazeStage(std::shared_ptr<const EyeModel> eyes, std::shared_ptr<const FaceModel> face);

/// Openness -> ARKit weights (docs/gaze.md): eyeBlink = clamp((0.8 - openness) / 0.55),
/// eyeWide = clamp((ratio - 1.1) / 0.3) with ratio the unclamped aperture ratio;
/// eyeLook: 1 at 30 degrees sideways, 25 up, 30 down.
float blinkWeight(float openness);
float wideWeight(float apertureRatio);
constexpr float kLookSidewaysFullDeg = 30.f;
constexpr float kLookUpFullDeg = 25.f;
constexpr float kLookDownFullDeg = 30.f;

/// The share of its looking-ahead lid gap an open eye keeps when looking down
/// by `pitchDeg` (<= 0), as the face model's eyeLookDown shapes lower the lids
/// at weight -pitch / kLookDownFullDeg: the gap between its upper and lower lid
/// landmarks over the eye width, relative to looking ahead, averaged over both
/// eyes; held beyond kLookDownFullDeg. Samples every 5 degrees from 0 down.
/// A model without eyeLookDown shapes: 1.2 % per degree down to 0.55.
class LidsFollowingGaze {
public:
    explicit LidsFollowingGaze(const FaceModel& face);
    float share(float pitchDeg) const;

private:
    static constexpr int kSamples = static_cast<int>(kLookDownFullDeg / 5.f) + 1;
    std::array<float, kSamples> share_{};
};

}  // namespace facetrack::gaze
