#include "still_landmarks.hpp"

#include "app/image_view.hpp"
#include "landmarks/lbf.hpp"
#include "model/internals.hpp"

#include <filesystem>

namespace facetrack::cli {

namespace {

/// The model at `given`, none for "none", or the shipped one at `shipped` when `given` is "" and it exists.
template <class Model>
std::shared_ptr<const Model> givenOrShipped(const std::string& given, const std::string& shipped) {
    if (given == "none") return nullptr;
    std::error_code ec;
    if (given.empty() && !std::filesystem::exists(shipped, ec)) return nullptr;
    return Model::load(given.empty() ? shipped : given);
}

}  // namespace

StillLandmarks::StillLandmarks(std::shared_ptr<const LandmarkModel> lbf, const std::string& refinerPath, const std::string& cascadePath,
                               bool lbfOnly, const std::string& boxPrior, int starts)
    : lbf_(std::move(lbf)), method_("facetrack LBF"), box_prior_(boxPrior), starts_(starts) {
    config_.filter.enabled = false;
    config_.max_faces = 1;
    config_.landmark_starts = starts;
    config_.detector.kind = boxPrior == "cascade" ? DetectorKind::Cascade : DetectorKind::YuNet;  // its kind picks LBF's box prior
    models_.landmarks = lbf_;
    if (lbfOnly) return;
    models_.refiner = givenOrShipped<RefinerModel>(refinerPath, RefinerModel::defaultPath());
    models_.cnn = givenOrShipped<CnnModel>(cascadePath, CnnModel::defaultPath());
    if (models_.cnn && !models_.cnn->hasLandmarkNet()) {
        if (!cascadePath.empty()) throw Error("CNN file '" + cascadePath + "' has no landmark net");
        models_.cnn = nullptr;  // the shipped one reads expressions only: the landmarks are the refiner's
    }
    if (!models_.refiner && !models_.cnn) return;
    method_ += std::string(models_.refiner ? " + refiner" : "") + (models_.cnn ? " + fit + CNN" : "");
    models_.face = FaceModel::loadDefault();
    tracker_ = std::make_unique<Tracker>(models_, config_);
}

const FaceResult* StillLandmarks::followed(const cv::Mat& bgr, bool newClip) {
    if (!follower_) {
        if (!models_.face) models_.face = FaceModel::loadDefault();
        follower_ = std::make_unique<Tracker>(models_, config_);
    }
    if (newClip) {
        follower_->reset();
        follower_time_ = 0.0;
    }
    follower_->process(tools::viewOf(bgr), follower_time_, followed_);
    follower_time_ += 1.0 / 30.0;
    return followed_.faces.empty() || !followed_.faces[0].landmarks ? nullptr : &followed_.faces[0];
}

Landmarks68 StillLandmarks::of(const cv::Mat& bgr, const cv::Mat& gray, const Box& box, bool* dropped) {
    if (dropped) *dropped = false;
    if (tracker_) {
        tracker_->reset();
        tracker_->process(tools::viewOf(bgr), 0.0, {box}, result_);
        if (!result_.faces.empty() && result_.faces[0].landmarks) return *result_.faces[0].landmarks;
        if (dropped) *dropped = true;
    }
    return core::toLandmarks68(
        landmarks::alignFromStarts(model::dataOf(*lbf_), gray, landmarks::shapeFromBox(model::dataOf(*lbf_), box, box_prior_), starts_));
}

}  // namespace facetrack::cli
