#include "core/onnx_net.hpp"

#include "facetrack/error.hpp"

namespace facetrack::core {

OnnxNet::OnnxNet(const std::string& onnx, std::array<int, 4> shape, int outputs, const std::string& what) {
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
}

const float* OnnxNet::forward() {
    net_.setInput(input_);
    net_.forward(outputs_);
    return outputs_[0].ptr<float>();
}

}  // namespace facetrack::core
