#pragma once
// The "refine" stage: the landmark refiner (landmark_refiner.hpp) moves the
// landmarks stage's 68 landmarks, before the fit reads them.
//
// Reads and writes: landmarks (and locates the face at their box).
// Never loses a face: the landmarks stage's checks decide that; a non-finite
// answer keeps LBF's landmarks.

#include "pipeline/stage.hpp"

#include "facetrack/refiner_model.hpp"

#include <memory>

namespace facetrack::refine {

/// `model` null: the stage is not available.
std::unique_ptr<pipeline::Stage> makeRefineStage(std::shared_ptr<const RefinerModel> model);

}  // namespace facetrack::refine
