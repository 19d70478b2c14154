#include "cnn/landmark_refiner.hpp"

#include "facetrack/error.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace facetrack::cnn {

RefinerLayout makeRefinerLayout(const CnnModelData& data) {
    if (data.refiner_mean.size() != 2 * landmarks::kLandmarks || data.refiner_share.size() != landmarks::kLandmarks) {
        throw Error("landmark refiner: needs a mean shape of 68 points and 68 shares");
    }
    RefinerLayout layout;
    layout.size = data.refiner_patch_size;
    layout.mean = Eigen::Map<const landmarks::Shape68>(data.refiner_mean.data());
    layout.share = Eigen::Map<const Eigen::Array<float, 1, 68>>(data.refiner_share.data());
    layout.trust_from = data.refiner_trust_from;
    layout.trust_to = data.refiner_trust_to;
    return layout;
}

float netTrust(const RefinerLayout& layout, const landmarks::Shape68& net, const landmarks::Shape68& lbf) {
    if (!(layout.trust_to > layout.trust_from)) return 0.f;
    const Eigen::Array2f extent = lbf.rowwise().maxCoeff().array() - lbf.rowwise().minCoeff().array();
    const float size = std::sqrt(std::max(extent.x() * extent.y(), 1e-6f));
    const float disagreement = (net - lbf).colwise().norm().mean() / size;
    return std::clamp((disagreement - layout.trust_from) / (layout.trust_to - layout.trust_from), 0.f, 1.f);
}

core::Similarity patchToFrame(const RefinerLayout& layout, const landmarks::Shape68& lbf) {
    return core::alignSimilarity(layout.mean, lbf);
}

void warpAligned(const RefinerLayout& layout, const cv::Mat& gray, const core::Similarity& toFrame, cv::Mat& patch) {
    const Eigen::Matrix2f a = toFrame.linear();
    const cv::Matx23d frameOf(a(0, 0), a(0, 1), toFrame.translation.x(), a(1, 0), a(1, 1), toFrame.translation.y());
    cv::warpAffine(gray, patch, frameOf, cv::Size(layout.size, layout.size), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
}

landmarks::Shape68 netLandmarks(const RefinerLayout& layout, const core::Similarity& toFrame, const Eigen::VectorXd& d) {
    return toFrame.apply(layout.mean + Eigen::Map<const Eigen::Matrix<double, 2, 68>>(d.data()).cast<float>());
}

landmarks::Shape68 blendedLandmarks(const RefinerLayout& layout, const landmarks::Shape68& net, const landmarks::Shape68& lbf, float trust) {
    const Eigen::Array<float, 1, 68> share = layout.share + trust * (1.f - layout.share);
    return (net.array().rowwise() * share + lbf.array().rowwise() * (1.f - share)).matrix();
}

landmarks::Shape68 refinedLandmarks(const RefinerLayout& layout, const core::Similarity& toFrame, const Eigen::VectorXd& d,
                                    const landmarks::Shape68& lbf) {
    const landmarks::Shape68 net = netLandmarks(layout, toFrame, d);
    return blendedLandmarks(layout, net, lbf, netTrust(layout, net, lbf));
}

}  // namespace facetrack::cnn
