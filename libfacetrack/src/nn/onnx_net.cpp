#include "nn/onnx_net.hpp"

#include "core/environment.hpp"
#include "facetrack/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace facetrack::nn {

namespace {

/// The largest difference between the own kernels' outputs and dnn's, over the
/// scale of dnn's, on a fixed input of values in [-2, 2] (as standardised patches).
double chainDiscrepancy(cv::dnn::Net& net, ConvChain& chain, cv::Mat& input) {
    float* x = input.ptr<float>();
    std::uint32_t state = 12345u;
    for (std::size_t k = 0; k < input.total(); ++k) {
        state = state * 1664525u + 1013904223u;  // a linear congruential generator: the same input on every machine
        x[k] = static_cast<float>(state >> 8) / static_cast<float>(1u << 24) * 4.0f - 2.0f;
    }
    net.setInput(input);
    const cv::Mat expected = net.forward().clone();
    std::vector<float> own(expected.total());
    chain.forward(x, own.data());
    input.setTo(0);
    double worst = 0.0, scale = 1.0;
    for (std::size_t k = 0; k < own.size(); ++k) {
        const double e = expected.ptr<float>()[k];
        scale = std::max(scale, std::abs(e));
        worst = std::max(worst, std::isfinite(own[k]) ? std::abs(own[k] - e) : HUGE_VAL);
    }
    return worst / scale;
}

}  // namespace

OnnxNet::Engine OnnxNet::defaultEngine() { return core::getEnv("FACETRACK_NET_ENGINE") == "opencv" ? Engine::OpenCvDnn : Engine::Own; }

OnnxNet::OnnxNet(const std::string& onnx, std::array<int, 4> shape, int outputs, const std::string& what, Engine engine) {
    try {
        net_ = cv::dnn::readNetFromONNX(onnx.data(), onnx.size());
    } catch (const cv::Exception& e) {
        throw Error(what + " does not load: " + e.what());
    }
    if (net_.empty()) throw Error(what + " does not load");
    input_.create(4, shape.data(), CV_32F);
    input_.setTo(0);
    const std::string size = std::to_string(shape[0]) + " x " + std::to_string(shape[1]) + " x " + std::to_string(shape[2]) + " x " +
                             std::to_string(shape[3]);
    net_.setInput(input_);
    try {
        net_.forward(outputs_);
    } catch (const cv::Exception& e) {
        throw Error(what + " does not run on a " + size + " input: " + e.what());
    }
    if (outputs_.size() != 1 || static_cast<int>(outputs_[0].total()) != outputs) {
        throw Error(what + " gives " + std::to_string(outputs_.empty() ? 0 : outputs_[0].total()) + " outputs for a " + size +
                    " input, not " + std::to_string(outputs));
    }
    if (engine != Engine::Own) return;
    std::string whyNot;
    std::optional<ConvChain> chain = ConvChain::fromNet(net_, shape, whyNot);
    if (chain && chain->outputsPerItem() * shape[0] != outputs) whyNot = "the chain read off it gives another number of outputs";
    if (chain && whyNot.empty()) {
        // Float sums in another order differ by ~1e-6 of the outputs' scale; a misread layer by far more.
        constexpr double kTolerance = 1e-4;
        const double discrepancy = chainDiscrepancy(net_, *chain, input_);
        if (discrepancy <= kTolerance) {
            chain_ = std::move(chain);
            chain_output_.assign(static_cast<std::size_t>(outputs), 0.0f);
            net_ = cv::dnn::Net();  // its weights and buffers are not needed again
            return;
        }
        whyNot = "its outputs differ from dnn's by " + std::to_string(discrepancy) + " of their scale";
    }
    core::log(what + " runs with OpenCV's dnn: " + whyNot);
}

const float* OnnxNet::forward() {
    if (chain_) {
        chain_->forward(input_.ptr<float>(), chain_output_.data());
        return chain_output_.data();
    }
    net_.setInput(input_);
    net_.forward(outputs_);
    return outputs_[0].ptr<float>();
}

}  // namespace facetrack::nn
