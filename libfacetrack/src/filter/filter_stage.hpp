#pragma once
// The "filter" stage, last in the list: the 1-euro filter (one_euro.hpp) on
// the landmarks, the head pose and the expression weights.
//
// Moves the unfiltered landmarks, pose and expression into FaceResult::raw and
// puts the filtered values in their place. Off (not available) when
// FilterConfig::enabled is false: the fields stay unfiltered and raw empty.

#include "pipeline/stage.hpp"

#include "facetrack/face_model.hpp"
#include "facetrack/tracker.hpp"

#include <memory>
#include <vector>

namespace facetrack::filter {

/// `model` converts the filtered native weights to ARKit. `passThrough`: native
/// expression indices left unfiltered, for a stage that does its own temporal
/// estimation (the gaze stage's eye shapes: a blink lasts 3-4 frames, and the
/// 1-euro filter would halve it).
std::unique_ptr<pipeline::Stage> makeFilterStage(std::shared_ptr<const FaceModel> model, const FilterConfig& config,
                                                 std::vector<int> passThrough = {});

}  // namespace facetrack::filter
