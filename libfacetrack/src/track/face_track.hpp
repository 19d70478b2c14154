#pragma once
// The state the Tracker keeps for one followed face.

#include "filter/one_euro.hpp"
#include "fit/face_fitter.hpp"
#include "landmarks/lbf_model.hpp"

#include "facetrack/geometry.hpp"

#include <memory>
#include <vector>

namespace facetrack::track {

struct FaceTrack {
    int id = 0;
    bool fresh = true;          ///< found by the detector this frame: start the landmarks from `box`
    Box box;                    ///< detector box (fresh) or the landmarks' bounds
    long last_frame = -1;       ///< the frame it was last advanced in
    int age = 0;                ///< frames followed
    bool lost = false;          ///< failed this frame: dropped before the results

    landmarks::Shape68 shape = landmarks::Shape68::Zero();  ///< this frame's landmarks, next frame's start
    std::unique_ptr<fit::FaceFitter> fitter;
    fit::FaceParams params;
    fit::ContourSlots contour{};
    double residual = 0.0;
    bool fitted = false;

    std::vector<fit::CalibrationFrame> calibration_window;
    bool identity_calibrated = false;

    filter::OneEuroFilter landmark_filter, rotation_filter, translation_filter, expression_filter;
    Eigen::Quaterniond last_rotation = Eigen::Quaterniond::Identity();  ///< keeps q and -q apart
};

}  // namespace facetrack::track
