#pragma once
/// \file
/// Everything in facetrack's public API. Each header states what it owns and
/// which of its calls may run on which threads.

#include "facetrack/arkit.hpp"
#include "facetrack/async_tracker.hpp"
#include "facetrack/calibration.hpp"
#include "facetrack/capture.hpp"
#include "facetrack/cnn_model.hpp"
#include "facetrack/detector.hpp"
#include "facetrack/error.hpp"
#include "facetrack/eye_model.hpp"
#include "facetrack/face_model.hpp"
#include "facetrack/geometry.hpp"
#include "facetrack/image.hpp"
#include "facetrack/landmark_model.hpp"
#include "facetrack/posed_mesh.hpp"
#include "facetrack/result.hpp"
#include "facetrack/tracker.hpp"
#include "facetrack/version.hpp"
