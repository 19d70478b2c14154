#pragma once
// The "cnn" stage (thesis 4.4): the CNN cascade refines the fit's pose and
// expressions from the face texture. Each stage of the cascade warps the
// frame into the canonical patch at the current parameters (face_warp.hpp),
// regresses the update (update_net.hpp) and applies it, `rounds` times.
//
// Reads: FaceResult::pose, expression, identity (the fit's). Writes: pose and
// the cascade's expressions (the others stay as the fit left them); a cascade
// that reads only expressions (CnnModel::expressionsOnly) writes only those the
// fit does not estimate. Never loses a face: the fit's checks decide that.

#include "pipeline/stage.hpp"

#include "facetrack/cnn_model.hpp"
#include "facetrack/face_model.hpp"

#include <memory>

namespace facetrack::cnn {

/// `cascade` null: the stage is not available; `fit` null or not available also (it refines the fit).
/// `fit`'s estimated expressions are the ones an expressions-only cascade leaves alone.
std::unique_ptr<pipeline::Stage> makeCnnStage(std::shared_ptr<const CnnModel> cascade, std::shared_ptr<const FaceModel> face,
                                              const pipeline::Stage* fit);

}  // namespace facetrack::cnn
