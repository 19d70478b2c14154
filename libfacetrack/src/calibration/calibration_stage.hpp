#pragma once
// The "calibration" stage, last in the list: the user's Calibration
// (facetrack/calibration.hpp) applied to the reported weights, so that their
// relaxed face reads 0 and their full expression reaches 1:
//   w' = min(g r', 1),  r' = dead zone d applied to r = clamp((w - w0) / (w1 - w0), 0, 1)
// for each ARKit weight; each of the face model's own weights the same way,
// with its own neutral and the w1, g and d of the ARKit shape it drives, so
// that a mesh posed from them (the demo's avatar, OpenSeeFace's points) moves
// as the ARKit weights do.
//
// Reads: expression. Writes: expression (not raw: raw stays as the stages
// estimated it). It keeps each face's last input, so that a neutral is taken
// from the weights as estimated, not as already calibrated
// (Stage::captureNeutral).

#include "pipeline/stage.hpp"

#include "facetrack/face_model.hpp"

#include <memory>

namespace facetrack::calibration {

std::unique_ptr<pipeline::Stage> makeCalibrationStage(std::shared_ptr<const FaceModel> model);

}  // namespace facetrack::calibration
