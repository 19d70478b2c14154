#pragma once
// A small ONNX net run with OpenCV's dnn on a fixed input shape: the CNN
// cascade's nets (cnn/patch_net.hpp) and the gaze stage's iris net. Loaded
// from the model file's bytes and tried once on a zero input, so that a net
// that does not load, or does not give the expected number of outputs for
// that shape, is an error at load time rather than mid-frame.

#include <opencv2/dnn.hpp>

#include <array>
#include <string>
#include <vector>

namespace facetrack::core {

class OnnxNet {
public:
    /// `shape`: the input blob's N x C x H x W; `outputs`: the values the net
    /// must give for it; `what` names the net in errors. Throws Error.
    OnnxNet(const std::string& onnx, std::array<int, 4> shape, int outputs, const std::string& what);

    /// The input blob (CV_32F, N x C x H x W), to fill before forward().
    cv::Mat& input() { return input_; }
    /// Runs the net on input(); the outputs, `outputs` floats, stay valid until
    /// the next call. Not thread-safe (the net keeps its buffers): one per thread.
    const float* forward();

private:
    cv::dnn::Net net_;
    cv::Mat input_;
    std::vector<cv::Mat> outputs_;
};

}  // namespace facetrack::core
