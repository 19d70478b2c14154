#pragma once
// A CNN on a square grey patch, run by nn::OnnxNet (the own kernels, or
// OpenCV's dnn): the cascade's stages' updates (update_net.hpp) and landmark
// displacements (landmark_net.hpp) on the face patch (face_warp.hpp), and the
// landmark and brow refiners (landmark_refiner.hpp). Trained by
// tools/train/expression/train_stage.py and tools/train/refine (docs/cnn.md).
//
// The net's input is the patch standardised per patch, (I - mean) / sigma
// (population sigma, I in [0, 1]), as the training script does. A net may
// read a batch of patches in one call (the brow and eye refiner's two sides):
// one call costs less than two.

#include "nn/onnx_net.hpp"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <span>
#include <string>

namespace facetrack::nn {

class PatchNet {
public:
    /// A net from an ONNX file's bytes; `what` names it in errors. Throws
    /// Error when it does not load or is not a net of batch x 1 x size x size
    /// -> batch x `outputs` values.
    PatchNet(const std::string& onnx, int patchSize, int outputs, const std::string& what, int batch = 1);

    /// The values per patch.
    int outputCount() const { return outputs_; }
    /// What runs the net (nn::OnnxNet::engineName).
    const char* engineName() const { return net_.engineName(); }

    /// The outputs for `patch` (CV_8U, patchSize x patchSize), for a net of
    /// batch 1. Not thread-safe (the net keeps its buffers): one per thread.
    const Eigen::VectorXd& predict(const cv::Mat& patch);
    /// The outputs for the batch's patches, patch b's at
    /// segment(b * outputCount(), outputCount()).
    const Eigen::VectorXd& predict(std::span<const cv::Mat> patches);

private:
    nn::OnnxNet net_;
    int size_;
    int outputs_;
    Eigen::VectorXd output_;  ///< batch x outputs_
};

}  // namespace facetrack::nn
