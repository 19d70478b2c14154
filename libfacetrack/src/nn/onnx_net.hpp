#pragma once
// A small ONNX net on a fixed input shape: the CNN cascade's nets
// (cnn/patch_net.hpp) and the gaze stage's iris net. Loaded from the model
// file's bytes with OpenCV's dnn and tried once on a zero input, so that a net
// that does not load, or does not give the expected number of outputs for that
// shape, is an error at load time rather than mid-frame.
//
// Two engines run it: the project's own kernels (conv_chain.hpp) where the net
// is a plain chain they run and they give dnn's outputs on a test input, else
// OpenCV's dnn. FACETRACK_NET_ENGINE=opencv chooses dnn for every net, to
// compare the two.

#include "nn/conv_chain.hpp"

#include <opencv2/dnn.hpp>

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace facetrack::nn {

class OnnxNet {
public:
    enum class Engine { Own, OpenCvDnn };

    /// `shape`: the input blob's N x C x H x W; `outputs`: the values the net
    /// must give for it; `what` names the net in errors. `engine` Own falls
    /// back to dnn (with a log line) for a net the own kernels do not run.
    /// Throws Error.
    OnnxNet(const std::string& onnx, std::array<int, 4> shape, int outputs, const std::string& what, Engine engine = defaultEngine());

    /// Own, or OpenCvDnn when FACETRACK_NET_ENGINE is "opencv".
    static Engine defaultEngine();
    /// The engine that runs the net.
    Engine engine() const { return chain_ ? Engine::Own : Engine::OpenCvDnn; }
    /// The engine, as the stages describe it: "own kernels" or "OpenCV's dnn".
    const char* engineName() const { return chain_ ? "own kernels" : "OpenCV's dnn"; }

    /// The input blob (CV_32F, N x C x H x W), to fill before forward().
    cv::Mat& input() { return input_; }
    /// Runs the net on input(); the outputs, `outputs` floats, stay valid until
    /// the next call. Not thread-safe (the net keeps its buffers): one per thread.
    const float* forward();

private:
    cv::dnn::Net net_;  ///< runs the net when the own kernels do not; emptied when they do
    std::optional<ConvChain> chain_;
    cv::Mat input_;
    std::vector<cv::Mat> outputs_;
    std::vector<float> chain_output_;
};

}  // namespace facetrack::nn
