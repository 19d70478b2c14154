#pragma once
// The landmark refiner (issue 17, docs/cnn.md): a CNN that moves LBF's 68
// landmarks, reading the face aligned by them.
//
// With m_i the refiner's mean shape in patch pixels and l_i LBF's landmarks,
// x -> A x + t is the least-squares similarity m -> l (core::alignSimilarity),
// and the patch is the frame sampled there: P(u) = I(A u + t), bilinear,
// borders replicated. The net (patch_net.hpp) regresses where the landmarks
// lie in the patch, as offsets from the mean shape, d (136 values:
// x_0, y_0, ..., patch pixels); back in the frame p_i = A (m_i + d_i) + t. The
// answer blends the two estimates,
//   q_i = w_i p_i + (1 - w_i) l_i,
// with w_i the net's share, chosen per face region on the validation split:
// the net and LBF err differently, and their blend beats either.

#include "core/shape2d.hpp"
#include "landmarks/lbf_model.hpp"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <vector>

namespace facetrack::cnn {

struct RefinerLayout {
    int size = 0;                       ///< the patch's side, pixels
    landmarks::Shape68 mean;            ///< m above
    Eigen::Array<float, 1, 68> share;  ///< w above
};

/// The layout a model file stores (cnn_model_data.hpp: 136 mean values, 68 shares).
RefinerLayout makeRefinerLayout(int size, const std::vector<float>& mean, const std::vector<float>& share);

/// x -> A x + t above, patch pixels to frame pixels.
core::Similarity patchToFrame(const RefinerLayout& layout, const landmarks::Shape68& lbf);

/// P above, into `patch` (8-bit grey, size x size; reused).
void warpAligned(const RefinerLayout& layout, const cv::Mat& gray, const core::Similarity& toFrame, cv::Mat& patch);

/// q above from the net's outputs d.
landmarks::Shape68 refinedLandmarks(const RefinerLayout& layout, const core::Similarity& toFrame, const Eigen::VectorXd& d,
                                    const landmarks::Shape68& lbf);

}  // namespace facetrack::cnn
