#include "refine/landmark_refiner.hpp"

#include "core/image.hpp"
#include "facetrack/error.hpp"
#include "nn/patch_net.hpp"

#include <algorithm>
#include <cmath>

namespace facetrack::refine {

RefinerLayout makeRefinerLayout(const nn::RefinerModelData& data) {
    if (data.mean.size() != 2 * core::kLandmarks || data.share.size() != core::kLandmarks) {
        throw Error("landmark refiner: needs a mean shape of 68 points and 68 shares");
    }
    RefinerLayout layout;
    layout.size = data.patch_size;
    layout.mean = Eigen::Map<const core::Shape68>(data.mean.data());
    layout.share = Eigen::Map<const Eigen::Array<float, 1, 68>>(data.share.data());
    layout.trust_from = data.trust_from;
    layout.trust_to = data.trust_to;
    return layout;
}

float netTrust(const RefinerLayout& layout, const core::Shape68& net, const core::Shape68& lbf) {
    if (!(layout.trust_to > layout.trust_from)) return 0.f;
    const Eigen::Array2f extent = lbf.rowwise().maxCoeff().array() - lbf.rowwise().minCoeff().array();
    const float size = std::sqrt(std::max(extent.x() * extent.y(), 1e-6f));
    const float disagreement = (net - lbf).colwise().norm().mean() / size;
    return std::clamp((disagreement - layout.trust_from) / (layout.trust_to - layout.trust_from), 0.f, 1.f);
}

core::Similarity patchToFrame(const RefinerLayout& layout, const core::Shape68& lbf) { return core::alignSimilarity(layout.mean, lbf); }

void warpAligned(const RefinerLayout& layout, const cv::Mat& gray, const core::Similarity& toFrame, cv::Mat& patch) {
    const Eigen::Matrix2f a = toFrame.linear();
    const cv::Matx23d frameOf(a(0, 0), a(0, 1), toFrame.translation.x(), a(1, 0), a(1, 1), toFrame.translation.y());
    core::warpAffineGray(gray, frameOf, cv::Size(layout.size, layout.size), patch);
}

core::Shape68 netLandmarks(const RefinerLayout& layout, const core::Similarity& toFrame, const Eigen::VectorXd& d) {
    return toFrame.apply(layout.mean + Eigen::Map<const Eigen::Matrix<double, 2, 68>>(d.data()).cast<float>());
}

core::Shape68 blendedLandmarks(const RefinerLayout& layout, const core::Shape68& net, const core::Shape68& lbf, float trust) {
    const Eigen::Array<float, 1, 68> share = layout.share + trust * (1.f - layout.share);
    return (net.array().rowwise() * share + lbf.array().rowwise() * (1.f - share)).matrix();
}

core::Shape68 refinedLandmarks(const RefinerLayout& layout, const core::Similarity& toFrame, const Eigen::VectorXd& d,
                               const core::Shape68& lbf) {
    const core::Shape68 net = netLandmarks(layout, toFrame, d);
    return blendedLandmarks(layout, net, lbf, netTrust(layout, net, lbf));
}

SideLayout makeSideLayout(const nn::RefinerModelData& data) {
    if (data.side_mean.size() != 22 || data.side_share.size() != 11) {
        throw Error("brow and eye refiner: needs a mean shape of 11 points and 11 shares");
    }
    SideLayout layout;
    layout.size = data.side_patch_size;
    layout.mean = Eigen::Map<const SideShape>(data.side_mean.data());
    layout.share = Eigen::Map<const Eigen::Array<float, 1, 11>>(data.side_share.data());
    return layout;
}

SideShape sidePoints(const core::Shape68& shape, bool mirrored, int width) {
    const auto& index = mirrored ? kLeftSide : kRightSide;
    SideShape side;
    for (std::size_t i = 0; i < index.size(); ++i) side.col(static_cast<Eigen::Index>(i)) = shape.col(index[i]);
    if (mirrored) side.row(0) = (static_cast<float>(width - 1) - side.row(0).array()).matrix();
    return side;
}

cv::Matx23d sidePatchToFrame(const SideLayout& layout, const SideShape& side, bool mirrored, int width) {
    const core::Similarity s = core::alignSimilarity(layout.mean, side);
    const Eigen::Matrix2f b = s.linear();
    const cv::Matx23d toFrame(b(0, 0), b(0, 1), s.translation.x(), b(1, 0), b(1, 1), s.translation.y());
    if (!mirrored) return toFrame;
    return {-toFrame(0, 0), -toFrame(0, 1), width - 1 - toFrame(0, 2), toFrame(1, 0), toFrame(1, 1), toFrame(1, 2)};
}

void warpSide(const SideLayout& layout, const cv::Mat& gray, const cv::Matx23d& toFrame, cv::Mat& patch) {
    core::warpAffineGray(gray, toFrame, cv::Size(layout.size, layout.size), patch);
}

void placeSide(const SideLayout& layout, const cv::Matx23d& toFrame, const Eigen::Ref<const Eigen::VectorXd>& e, bool mirrored,
               core::Shape68& shape) {
    const auto& index = mirrored ? kLeftSide : kRightSide;
    const SideShape patch = layout.mean + Eigen::Map<const Eigen::Matrix<double, 2, 11>>(e.data()).cast<float>();
    for (std::size_t i = 0; i < index.size(); ++i) {
        const auto u = static_cast<double>(patch(0, static_cast<Eigen::Index>(i)));
        const auto v = static_cast<double>(patch(1, static_cast<Eigen::Index>(i)));
        const Eigen::Vector2f net(static_cast<float>(toFrame(0, 0) * u + toFrame(0, 1) * v + toFrame(0, 2)),
                                  static_cast<float>(toFrame(1, 0) * u + toFrame(1, 1) * v + toFrame(1, 2)));
        const float w = layout.share[static_cast<Eigen::Index>(i)];
        shape.col(index[i]) = w * net + (1.f - w) * shape.col(index[i]);
    }
}

void refineSides(const SideLayout& layout, nn::PatchNet& net, const cv::Mat& gray, std::array<cv::Mat, 2>& patches, core::Shape68& shape) {
    const int width = gray.cols;
    std::array<cv::Matx23d, 2> toFrame;
    for (const int b : {0, 1}) {  // the right side, then the left mirrored
        toFrame[b] = sidePatchToFrame(layout, sidePoints(shape, b == 1, width), b == 1, width);
        warpSide(layout, gray, toFrame[b], patches[b]);
    }
    const Eigen::VectorXd& e = net.predict(patches);
    const int n = net.outputCount();
    for (const int b : {0, 1}) {
        core::Shape68 placed = shape;
        placeSide(layout, toFrame[b], e.segment(b * n, n), b == 1, placed);
        if (placed.allFinite()) shape = placed;
    }
}

}  // namespace facetrack::refine
