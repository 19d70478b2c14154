#pragma once
// The "filter" stage, last in the list: the 1-euro filter (one_euro.hpp) on
// the landmarks, the head pose and the expression weights.
//
// Reads nothing it needs; writes raw (the unfiltered landmarks, pose and
// expression) and puts the filtered values in their place. Expressions an
// earlier stage smooths itself (Contract::expressions_smoothed: the gaze
// stage's eye shapes; a blink lasts 3-4 frames, and the 1-euro filter would
// halve it) pass through as they are. Off (not available) when
// TrackerConfig::filter.enabled is false: the fields stay unfiltered and raw empty.

#include "pipeline/stage.hpp"

#include "core/one_euro.hpp"
#include "facetrack/face_model.hpp"

#include <memory>
#include <vector>

namespace facetrack::filter {

/// `model` converts the filtered native weights to ARKit; `settings` are
/// TrackerConfig::filter's cutoffs; `enabled` false: not available.
std::unique_ptr<pipeline::Stage> makeFilterStage(std::shared_ptr<const FaceModel> model, const core::OneEuroSettings& settings,
                                                 bool enabled);

}  // namespace facetrack::filter
