#pragma once
// The "fit" stage: head pose and expression fitted to the landmarks (Ceres,
// face_fitter.hpp), cold for a new face and warm from the previous frame
// after that; and the user's identity, estimated once from a window of
// well-fitted frames, then frozen (calibrateIdentity).
//
// Reads: landmarks. Writes: pose, expression, identity (and
// identity_calibrated), fit (fit_residual, confidence), and next start (the
// fitted face's projection, where the next frame's landmark search starts).
// Lost: the residual exceeds max_residual, |pitch| > 70 deg, |yaw| > 80 deg,
// or the depth leaves [10 cm, 10 m]. Doubtful: the residual exceeds 3/4 of
// max_residual or the head turned more than kDoubtfulTurnDeg since the
// previous frame, what a fit that slid off a fast-moving face onto its side
// looks like. Unsettled: it turned more than kUnsettledTurnDeg.

#include "pipeline/stage.hpp"

#include "facetrack/face_model.hpp"

#include <memory>

namespace facetrack::fit {

struct FitStageSettings {
    float max_residual = 0.12f;    ///< TrackerConfig::max_fit_residual
    int calibration_frames = 30;   ///< TrackerConfig::calibration_frames
    float expression_prior = 1.f;  ///< TrackerConfig::expression_prior: a factor on FitSettings::expression_l2
};

std::unique_ptr<pipeline::Stage> makeFitStage(std::shared_ptr<const FaceModel> model, const FitStageSettings& settings);

}  // namespace facetrack::fit
