#pragma once
// A CNN of the cascade (thesis 4.4) on the face patch (face_warp.hpp), run
// with OpenCV's dnn: the stages' updates (update_net.hpp) and the landmark
// displacements (landmark_net.hpp). Trained by tools/train_cnn/train_stage.py
// (docs/cnn.md).
//
// The net's input is the patch standardised per patch, (I - mean) / sigma
// (population sigma, I in [0, 1]), as the training script does.

#include "core/onnx_net.hpp"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <string>

namespace facetrack::cnn {

class PatchNet {
public:
    /// A net from an ONNX file's bytes; `what` names it in errors. Throws
    /// Error when it does not load or is not a net of 1 x size x size ->
    /// `outputs` values.
    PatchNet(const std::string& onnx, int patchSize, int outputs, const std::string& what);

    int outputCount() const { return static_cast<int>(output_.size()); }

    /// The outputs for `patch` (CV_8U, patchSize x patchSize). Not thread-safe
    /// (the net keeps its buffers): one per thread.
    const Eigen::VectorXd& predict(const cv::Mat& patch);

private:
    core::OnnxNet net_;
    int size_;
    Eigen::VectorXd output_;
};

}  // namespace facetrack::cnn
