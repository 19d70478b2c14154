#pragma once
// The 68 landmarks of a face in a still image, from a box, the way users get
// them: the whole pipeline (LBF, the landmark refiner, the fit, the CNN cascade
// with its landmark net: docs/cnn.md), or LBF alone (`landmarks` and
// `eval-landmarks` report the pipeline's by default).

#include "facetrack/facetrack.hpp"

#include <opencv2/core.hpp>

#include <memory>
#include <string>

namespace facetrack::cli {

class StillLandmarks {
public:
    /// `refinerPath`: a landmark refiner, "" for the shipped one when it exists, or "none".
    /// `cascadePath`: a CNN file with a landmark net, "" for the shipped one when it has one, or
    /// "none"; a given file without one is an Error. `lbfOnly`, or neither: LBF alone.
    /// `boxPrior`: the detector whose boxes are given, "yunet" or "cascade".
    /// `starts`: LBF from that many starts, averaged (TrackerConfig::landmark_starts).
    StillLandmarks(std::shared_ptr<const LandmarkModel> lbf, const std::string& refinerPath, const std::string& cascadePath, bool lbfOnly,
                   const std::string& boxPrior = "yunet", int starts = TrackerConfig{}.landmark_starts);

    /// What the landmarks are: "facetrack LBF", with " + refiner" and " + fit + CNN" for the nets that move them.
    const std::string& method() const { return method_; }
    bool usesPipeline() const { return tracker_ != nullptr; }

    /// The landmarks of the face in `box`. Where the
    /// pipeline drops the face (its fit does not hold), LBF's; `dropped` says so.
    Landmarks68 of(const cv::Mat& bgr, const cv::Mat& gray, const Box& box, bool* dropped = nullptr);

    /// The same stages as a video application runs them: `bgr` is the next
    /// frame of a clip at 30 fps (the first of a new one when `newClip`), the
    /// tracker's own detector finds the face and tracking mode follows it (no
    /// filter). The followed face (valid until the next call), or null on a
    /// frame where it follows none.
    const FaceResult* followed(const cv::Mat& bgr, bool newClip);

private:
    std::shared_ptr<const LandmarkModel> lbf_;
    Models models_;
    TrackerConfig config_;
    std::unique_ptr<Tracker> tracker_, follower_;
    double follower_time_ = 0.0;
    FrameResult result_, followed_;
    std::string method_, box_prior_;
    int starts_;
};

}  // namespace facetrack::cli
