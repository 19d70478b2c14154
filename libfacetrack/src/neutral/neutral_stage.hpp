#pragma once
// The "neutral" stage, last in the list: the user's neutral expression
// (Tracker::calibrateNeutral) subtracted from the reported weights. With w0 a
// weight's value on the neutral face, it reports
//   w' = clamp((w - w0) / (1 - w0), 0, 1),
// so the relaxed face reads 0 and a full expression still reaches 1. The eyes'
// look directions are left alone: a neutral face may look anywhere.
//
// Reads: expression. Writes: expression (not raw: raw stays as the stages
// estimated it). Without a neutral it passes the weights through. It keeps
// each frame's input, so that a calibration takes the weights as estimated,
// not as already rescaled.

#include "pipeline/stage.hpp"

#include "facetrack/face_model.hpp"

#include <memory>

namespace facetrack::neutral {

std::unique_ptr<pipeline::Stage> makeNeutralStage(std::shared_ptr<const FaceModel> model);

}  // namespace facetrack::neutral
