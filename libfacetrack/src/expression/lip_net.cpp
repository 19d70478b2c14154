#include "expression/lip_net.hpp"

#include "core/image.hpp"

#include <opencv2/core.hpp>

namespace facetrack::expression {

const std::array<int, nn::kLipPoints> kLipMirror = {10, 9,  8,  7,  6,  5,  4,  3,  2,  1,  0,  19, 18, 17, 16, 15, 14, 13, 12, 11,
                                                    30, 29, 28, 27, 26, 25, 24, 23, 22, 21, 20, 39, 38, 37, 36, 35, 34, 33, 32, 31};

LipPoints mirroredLips(const LipPoints& lips) {
    LipPoints m;
    for (int k = 0; k < nn::kLipPoints; ++k) {
        const int from = kLipMirror[static_cast<std::size_t>(k)];
        m.col(k) << -lips(0, from), lips(1, from);
    }
    return m;
}

MouthPatch mouthPatch(const core::Shape68& points, int size, float half) {
    const NormalisingFrame frame = normalisingFrame(points);
    // a: the mouth's height in the normalised frame, centred across
    const Eigen::Matrix<float, 2, 20> mouth = frame.unroll() * (points.middleCols<20>(48).colwise() - frame.centre) / frame.rms;
    const Eigen::Vector2f anchor(0.f, mouth.row(1).mean());
    const Eigen::Matrix2f roll = frame.unroll().transpose();  // R(theta)
    const Eigen::Matrix2f a = frame.rms * roll * (2.f * half / static_cast<float>(size));
    const Eigen::Vector2f t = frame.centre +
                              frame.rms * roll * (anchor + Eigen::Vector2f::Constant(half * (1.f / static_cast<float>(size) - 1.f)));
    return {{a(0, 0), a(0, 1), t.x(), a(1, 0), a(1, 1), t.y()}, anchor};
}

LipNet::LipNet(const std::string& onnx, int size, float half, const std::string& what)
    : net_(onnx, size, 2 * nn::kLipPoints, what, 2), size_(size), half_(half) {}

const LipPoints& LipNet::predict(const cv::Mat& gray, const core::Shape68& points) {
    const MouthPatch mouth = mouthPatch(points, size_, half_);
    core::warpAffineGray(gray, mouth.to_frame, cv::Size(size_, size_), patches_[0]);
    cv::flip(patches_[0], patches_[1], 1);
    const Eigen::VectorXd& out = net_.predict(patches_);
    const LipPoints direct = Eigen::Map<const Eigen::Matrix<double, 2, nn::kLipPoints>>(out.data()).cast<float>();
    const LipPoints flipped = Eigen::Map<const Eigen::Matrix<double, 2, nn::kLipPoints>>(out.data() + 2 * nn::kLipPoints).cast<float>();
    lips_ = ((direct + mirroredLips(flipped)) * (0.5f * half_)).colwise() + mouth.anchor;
    return lips_;
}

}  // namespace facetrack::expression
