#pragma once
// eval-gaze's synthetic part: the face model rendered with a textured iris at
// known gaze (a software rasteriser, eval_gaze_synthetic.cpp), tracked, and
// the estimated gaze compared with the rendered one.

#include "facetrack/tracker.hpp"

namespace facetrack::cli {

/// `bareFaces`: renders without brows and lips (SyntheticRenderer's markings).
void evalSyntheticGaze(int renders, const Models& models, const TrackerConfig& config, bool bareFaces = false);

}  // namespace facetrack::cli
