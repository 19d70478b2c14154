#include "cnn/patch_net.hpp"

#include "facetrack/error.hpp"

#include <algorithm>

namespace facetrack::cnn {

PatchNet::PatchNet(const std::string& onnx, int patchSize, int outputs, const std::string& what) : size_(patchSize), output_(outputs) {
    try {
        net_ = cv::dnn::readNetFromONNX(onnx.data(), onnx.size());
    } catch (const cv::Exception& e) {
        throw Error(what + " does not load: " + e.what());
    }
    if (net_.empty()) throw Error(what + " does not load");
    const int sizes[] = {1, 1, size_, size_};
    input_.create(4, sizes, CV_32F);
    input_.setTo(0);
    net_.setInput(input_);
    try {
        net_.forward(outputs_);
    } catch (const cv::Exception& e) {
        throw Error(what + " does not run on a " + std::to_string(size_) + " px patch: " + e.what());
    }
    if (outputs_.size() != 1 || static_cast<int>(outputs_[0].total()) != outputs) {
        throw Error(what + " gives " + std::to_string(outputs_.empty() ? 0 : outputs_[0].total()) + " outputs, not " +
                    std::to_string(outputs));
    }
}

const Eigen::VectorXd& PatchNet::predict(const cv::Mat& patch) {
    if (patch.type() != CV_8UC1 || patch.rows != size_ || patch.cols != size_)
        throw Error("PatchNet: the patch must be 8-bit grey, " + std::to_string(size_) + " square");
    cv::Scalar mean, sigma;
    cv::meanStdDev(patch, mean, sigma);
    const double scale = 1.0 / std::max(sigma[0], 255.0 * 1e-3);
    cv::Mat plane(size_, size_, CV_32F, input_.ptr<float>());
    patch.convertTo(plane, CV_32F, scale, -mean[0] * scale);
    net_.setInput(input_);
    net_.forward(outputs_);
    const float* out = outputs_[0].ptr<float>();
    for (Eigen::Index k = 0; k < output_.size(); ++k) output_[k] = out[k];
    return output_;
}

}  // namespace facetrack::cnn
