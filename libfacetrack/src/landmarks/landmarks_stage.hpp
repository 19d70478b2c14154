#pragma once
// The "landmarks" stage: 68 2D landmarks by LBF regression (lbf.hpp), started
// from the detector's box for a new face, else from where the previous frame's
// fit projected them (FaceTrack::next_start).
//
// The cascade runs from several starts a few pixels apart and averages them
// (TrackerConfig::landmark_starts): less jitter than one start.
//
// Fills: FaceResult::landmarks (unfiltered here; the filter stage smooths
// them). Locates the face at the landmarks' bounding box. Loses the face when
// a quarter of the landmarks leave the frame, the eyes are closer than 8 px,
// or the landmarks' box has no texture (a covered lens, a blanked frame).

#include "pipeline/stage.hpp"

#include "facetrack/landmark_model.hpp"

#include <memory>
#include <string>

namespace facetrack::landmarks {

/// `model` null: the stage is not available. `detectorKind` ("yunet",
/// "cascade") picks the model's box prior for new faces. `starts`: the
/// cascade runs from that many starts and averages them (alignFromStarts).
std::unique_ptr<pipeline::Stage> makeLandmarksStage(std::shared_ptr<const LandmarkModel> model, std::string detectorKind, int starts);

}  // namespace facetrack::landmarks
