#include "nn/patch_net.hpp"

#include "facetrack/error.hpp"

#include <algorithm>

namespace facetrack::nn {

PatchNet::PatchNet(const std::string& onnx, int patchSize, int outputs, const std::string& what, int batch)
    : net_(onnx, {batch, 1, patchSize, patchSize}, batch * outputs, what), size_(patchSize), outputs_(outputs), output_(batch * outputs) {}

const Eigen::VectorXd& PatchNet::predict(const cv::Mat& patch) { return predict(std::span<const cv::Mat>(&patch, 1)); }

const Eigen::VectorXd& PatchNet::predict(std::span<const cv::Mat> patches) {
    if (static_cast<Eigen::Index>(patches.size()) * outputs_ != output_.size())
        throw Error("PatchNet: " + std::to_string(patches.size()) + " patches for a net of batch " +
                    std::to_string(output_.size() / outputs_));
    for (std::size_t b = 0; b < patches.size(); ++b) {
        const cv::Mat& patch = patches[b];
        if (patch.type() != CV_8UC1 || patch.rows != size_ || patch.cols != size_)
            throw Error("PatchNet: the patch must be 8-bit grey, " + std::to_string(size_) + " square");
        cv::Scalar mean, sigma;
        cv::meanStdDev(patch, mean, sigma);
        const double scale = 1.0 / std::max(sigma[0], 255.0 * 1e-3);
        cv::Mat plane(size_, size_, CV_32F, net_.input().ptr<float>() + b * static_cast<std::size_t>(size_ * size_));
        patch.convertTo(plane, CV_32F, scale, -mean[0] * scale);
    }
    const float* out = net_.forward();
    for (Eigen::Index k = 0; k < output_.size(); ++k) output_[k] = out[k];
    return output_;
}

}  // namespace facetrack::nn
