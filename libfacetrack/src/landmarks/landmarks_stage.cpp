#include "landmarks/landmarks_stage.hpp"

#include "core/box.hpp"
#include "core/shape2d.hpp"
#include "landmarks/lbf.hpp"
#include "model/internals.hpp"

#include <opencv2/imgproc.hpp>

namespace facetrack::landmarks {

namespace {

// Beyond these the face is lost.
constexpr float kMaxOutsideShare = 0.25f;  // landmarks outside the frame
constexpr float kMinEyeCornersPx = 8.f;
constexpr double kMinFaceContrast = 4.0;  // grey-level standard deviation inside the landmarks' box

/// A face has texture: on a covered lens or a blanked frame the regression
/// still returns a plausible shape.
bool hasTexture(const cv::Mat& gray, const Box& box) {
    const cv::Rect region = cv::Rect(cvRound(box.x0), cvRound(box.y0), cvRound(box.width()) + 1, cvRound(box.height()) + 1) &
                            cv::Rect(0, 0, gray.cols, gray.rows);
    if (region.area() <= 0) return false;
    cv::Scalar mean, deviation;
    cv::meanStdDev(gray(region), mean, deviation);
    return deviation[0] >= kMinFaceContrast;
}

/// A followed face's start: halfway between the previous frame's fitted face,
/// projected, and the model's mean shape placed on it by the least-squares
/// similarity. The projection places the face and carries its pose's outline,
/// but its shape follows the face model's landmark convention, which the
/// cascade, trained from mean shapes on boxes and shapes near the truth, hardly
/// corrects: started from the projection, a still face's 300-W validation NME
/// goes 3.61 % -> 4.48 % in five frames. Shares of the projection 0 / 0.25 / 0.5 /
/// 0.75 gave 3.81 / 3.73 / 3.70 / 4.02 % (docs/landmarks.md). Starting from
/// the previous landmarks themselves lets their errors accumulate.
constexpr float kProjectionShare = 0.5f;

Shape68 followingStart(const LbfModel& lbf, const Shape68& projection) {
    const Shape68 placedMean = core::alignSimilarity(lbf.mean_shape, projection).apply(lbf.mean_shape);
    return kProjectionShare * projection + (1.f - kProjectionShare) * placedMean;
}

class LandmarksStage final : public pipeline::Stage {
public:
    LandmarksStage(std::shared_ptr<const LandmarkModel> model, std::string detectorKind, int starts)
        : model_(std::move(model)), detector_kind_(std::move(detectorKind)), starts_(starts) {}

    StageInfo info() const override {
        if (!model_) return {"landmarks", false, "not available: no landmark model loaded"};
        return {"landmarks", true,
                "LBF, " + std::to_string(model_->stageCount()) + " stages, " + std::to_string(starts_) + " starts averaged (" +
                    model_->sourcePath() + ")"};
    }

    pipeline::Contract contract() const override { return {{}, pipeline::Field::Landmarks}; }

    pipeline::Outcome run(const pipeline::FrameInput& frame, pipeline::FaceTrack& face, pipeline::StageState*) override {
        const LbfModel& lbf = model::dataOf(*model_);
        const Shape68 start = face.fresh || !face.next_start ? shapeFromBox(lbf, face.box, detector_kind_)
                                                             : followingStart(lbf, core::fromLandmarks68(*face.next_start));
        const Shape68 shape = alignFromStarts(lbf, frame.gray, start, starts_);
        if (!shape.allFinite()) return pipeline::Outcome::Lost;
        face.result.landmarks = core::toLandmarks68(shape);
        face.locate(core::boundsOf(shape));

        const Box image{0.f, 0.f, static_cast<float>(frame.gray.cols - 1), static_cast<float>(frame.gray.rows - 1)};
        int outside = 0;
        for (int i = 0; i < kLandmarks; ++i) outside += !core::contains(image, shape(0, i), shape(1, i));
        const bool aFace = outside <= kMaxOutsideShare * kLandmarks && (shape.col(36) - shape.col(45)).norm() >= kMinEyeCornersPx &&
                           hasTexture(frame.gray, face.box);
        return aFace ? pipeline::Outcome::Ok : pipeline::Outcome::Lost;
    }

private:
    std::shared_ptr<const LandmarkModel> model_;
    std::string detector_kind_;
    int starts_;
};

}  // namespace

std::unique_ptr<pipeline::Stage> makeLandmarksStage(std::shared_ptr<const LandmarkModel> model, std::string detectorKind, int starts) {
    return std::make_unique<LandmarksStage>(std::move(model), std::move(detectorKind), starts);
}

}  // namespace facetrack::landmarks
