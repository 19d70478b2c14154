#include "cnn/landmark_refiner.hpp"

#include "facetrack/error.hpp"

#include <opencv2/imgproc.hpp>

namespace facetrack::cnn {

RefinerLayout makeRefinerLayout(int size, const std::vector<float>& mean, const std::vector<float>& share) {
    if (mean.size() != 2 * landmarks::kLandmarks || share.size() != landmarks::kLandmarks) {
        throw Error("landmark refiner: needs a mean shape of 68 points and 68 shares");
    }
    RefinerLayout layout;
    layout.size = size;
    layout.mean = Eigen::Map<const landmarks::Shape68>(mean.data());
    layout.share = Eigen::Map<const Eigen::Array<float, 1, 68>>(share.data());
    return layout;
}

core::Similarity patchToFrame(const RefinerLayout& layout, const landmarks::Shape68& lbf) {
    return core::alignSimilarity(layout.mean, lbf);
}

void warpAligned(const RefinerLayout& layout, const cv::Mat& gray, const core::Similarity& toFrame, cv::Mat& patch) {
    const Eigen::Matrix2f a = toFrame.linear();
    const cv::Matx23d frameOf(a(0, 0), a(0, 1), toFrame.translation.x(), a(1, 0), a(1, 1), toFrame.translation.y());
    cv::warpAffine(gray, patch, frameOf, cv::Size(layout.size, layout.size), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
}

landmarks::Shape68 refinedLandmarks(const RefinerLayout& layout, const core::Similarity& toFrame, const Eigen::VectorXd& d,
                                    const landmarks::Shape68& lbf) {
    const landmarks::Shape68 inPatch = layout.mean + Eigen::Map<const Eigen::Matrix<double, 2, 68>>(d.data()).cast<float>();
    const landmarks::Shape68 net = toFrame.apply(inPatch);
    return (net.array().rowwise() * layout.share + lbf.array().rowwise() * (1.f - layout.share)).matrix();
}

}  // namespace facetrack::cnn
