#pragma once
// The "cnn" stage (thesis 4.4): the CNN cascade refines the fit's pose and
// expressions from the face texture. Each stage of the cascade warps the
// frame into the canonical patch at the current parameters (face_warp.hpp),
// regresses the update (update_net.hpp) and applies it, `rounds` times.
//
// Reads: pose, expression, identity (the fit's), and the landmarks when the
// file has a geometry net (geometry_net.hpp: its expressions are read from the
// landmarks' shape instead of the texture). Writes: pose and the cascade's
// expressions (the others stay as the fit left them), and landmarks when the
// file has a landmark net; a cascade that reads only expressions
// (CnnModel::expressionsOnly) writes those no earlier stage estimates, and
// with corrects_fit the fit's too (the shipped file).
// Never loses a face: the fit's checks decide that.

#include "pipeline/stage.hpp"

#include "facetrack/cnn_model.hpp"
#include "facetrack/face_model.hpp"

#include <memory>

namespace facetrack::expression {

/// `cascade` null or without cascade stages: the stage is not available.
std::unique_ptr<pipeline::Stage> makeCnnStage(std::shared_ptr<const CnnModel> cascade, std::shared_ptr<const FaceModel> face);

}  // namespace facetrack::expression
