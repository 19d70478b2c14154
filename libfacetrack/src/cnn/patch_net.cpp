#include "cnn/patch_net.hpp"

#include "facetrack/error.hpp"

#include <algorithm>

namespace facetrack::cnn {

PatchNet::PatchNet(const std::string& onnx, int patchSize, int outputs, const std::string& what)
    : net_(onnx, {1, 1, patchSize, patchSize}, outputs, what), size_(patchSize), output_(outputs) {}

const Eigen::VectorXd& PatchNet::predict(const cv::Mat& patch) {
    if (patch.type() != CV_8UC1 || patch.rows != size_ || patch.cols != size_)
        throw Error("PatchNet: the patch must be 8-bit grey, " + std::to_string(size_) + " square");
    cv::Scalar mean, sigma;
    cv::meanStdDev(patch, mean, sigma);
    const double scale = 1.0 / std::max(sigma[0], 255.0 * 1e-3);
    cv::Mat plane(size_, size_, CV_32F, net_.input().ptr<float>());
    patch.convertTo(plane, CV_32F, scale, -mean[0] * scale);
    const float* out = net_.forward();
    for (Eigen::Index k = 0; k < output_.size(); ++k) output_[k] = out[k];
    return output_;
}

}  // namespace facetrack::cnn
