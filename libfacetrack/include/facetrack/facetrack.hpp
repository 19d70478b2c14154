#pragma once
/// \file
/// Everything in facetrack's public API.

#include "facetrack/arkit.hpp"
#include "facetrack/capture.hpp"
#include "facetrack/detector.hpp"
#include "facetrack/error.hpp"
#include "facetrack/face_model.hpp"
#include "facetrack/geometry.hpp"
#include "facetrack/image.hpp"
#include "facetrack/landmark_model.hpp"
#include "facetrack/result.hpp"
#include "facetrack/tracker.hpp"
#include "facetrack/version.hpp"
