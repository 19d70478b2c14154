#pragma once
// The landmark refiner (docs/cnn.md): a CNN that moves LBF's 68
// landmarks, reading the face aligned by them.
//
// With m_i the refiner's mean shape in patch pixels and l_i LBF's landmarks,
// x -> A x + t is the least-squares similarity m -> l (core::alignSimilarity),
// and the patch is the frame sampled there: P(u) = I(A u + t), bilinear,
// borders replicated. The net (patch_net.hpp) regresses where the landmarks
// lie in the patch, as offsets from the mean shape, d (136 values:
// x_0, y_0, ..., patch pixels); back in the frame p_i = A (m_i + d_i) + t. The
// answer blends the two estimates,
//   q_i = w'_i p_i + (1 - w'_i) l_i,   w'_i = w_i + g (1 - w_i),
// with w_i the net's share, chosen per face region on the validation split:
// the net and LBF err differently, and their blend beats either. g trusts the
// net alone where it disagrees with LBF by much: with D the mean |p_i - l_i|
// over sqrt(w h) of LBF's box, g = clamp((D - D0) / (D1 - D0), 0, 1) (0 when
// D1 <= D0). LBF fails on faces turned far, and a net trained on such faces
// (face profiling) does not: a wide disagreement is LBF's error (docs/cnn.md).
// While a face is followed, the refine stage averages g over frames,
// g_t = (g + g_{t-1}) / 2: a disagreement hovering in the ramp would otherwise
// switch the answer between blends from frame to frame (jitter).
// Where g > 0, LBF's points, which aligned the patch, are in doubt: the stage
// runs a second round, the patch aligned on q instead of l, and blends that
// answer p' with l the same way (its own g). On the turned validation copies
// at 45-60 deg of yaw that takes the error from 3.58 to 3.09 % of the box
// (docs/cnn.md).

//
// One side at a time (format version 6): a second net moves the brow and eye
// points of the answer q, the subject's right side (points 17-21, 36-41) as
// it is and the left side mirrored into its layout (kLeftSide), so one net
// reads both. With s the side's 11 points of q in that (mirrored) frame and
// n_i its mean shape, x -> B x + c is the similarity n -> s, the patch is
// P(u) = I(M(B u + c)), M the frame's mirror x -> W - 1 - x for the left side
// (else the identity), and the net's offsets e put the points at
// M(B (n_i + e_i) + c); each is blended with q by its own share v_i. The
// brows and eyes are thin: a patch of one side sees them at about twice the
// face patch's resolution (docs/cnn.md). The refine stage reads
// both sides' patches in one call of the net.

#include "core/shape2d.hpp"
#include "nn/refiner_model_data.hpp"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <array>
#include <vector>

namespace facetrack::nn {
class PatchNet;
}

namespace facetrack::refine {

struct RefinerLayout {
    int size = 0;                            ///< the patch's side, pixels
    core::Shape68 mean;                      ///< m above
    Eigen::Array<float, 1, 68> share;        ///< w above
    float trust_from = 0.f, trust_to = 0.f;  ///< D0, D1 above
};

/// The layout a model file stores (cnn_model_data.hpp: patch size, 136 mean values, 68 shares, D0, D1).
RefinerLayout makeRefinerLayout(const nn::RefinerModelData& data);

/// g above: how far the net alone is trusted, in [0, 1].
float netTrust(const RefinerLayout& layout, const core::Shape68& net, const core::Shape68& lbf);

/// x -> A x + t above, patch pixels to frame pixels.
core::Similarity patchToFrame(const RefinerLayout& layout, const core::Shape68& lbf);

/// P above, into `patch` (8-bit grey, size x size; reused).
void warpAligned(const RefinerLayout& layout, const cv::Mat& gray, const core::Similarity& toFrame, cv::Mat& patch);

/// The net's points p above from its outputs d.
core::Shape68 netLandmarks(const RefinerLayout& layout, const core::Similarity& toFrame, const Eigen::VectorXd& d);

/// q above, with the trust g.
core::Shape68 blendedLandmarks(const RefinerLayout& layout, const core::Shape68& net, const core::Shape68& lbf, float trust);

/// One side's brow and eye points, the subject's right side: its brow, then its eye.
constexpr std::array<int, 11> kRightSide = {17, 18, 19, 20, 21, 36, 37, 38, 39, 40, 41};
/// The left side's points that mirror kRightSide's, in the same order.
constexpr std::array<int, 11> kLeftSide = {26, 25, 24, 23, 22, 45, 44, 43, 42, 47, 46};
using SideShape = Eigen::Matrix<float, 2, 11>;

struct SideLayout {
    int size = 0;                      ///< the patch's side, pixels
    SideShape mean;                    ///< n above
    Eigen::Array<float, 1, 11> share;  ///< v above
};

/// The layout a model file stores (cnn_model_data.hpp: patch size, 22 mean values, 11 shares).
SideLayout makeSideLayout(const nn::RefinerModelData& data);

/// One side of `shape` in its patch's frame: `mirrored` (the left side) mirrors x in a frame
/// `width` pixels wide.
SideShape sidePoints(const core::Shape68& shape, bool mirrored, int width);

/// The 2 x 3 map from patch pixels to frame pixels, M(B u + c) above.
cv::Matx23d sidePatchToFrame(const SideLayout& layout, const SideShape& side, bool mirrored, int width);

/// P above, into `patch` (8-bit grey, size x size; reused).
void warpSide(const SideLayout& layout, const cv::Mat& gray, const cv::Matx23d& toFrame, cv::Mat& patch);

/// `shape` with one side's 11 points moved to the net's outputs e (22 values: x_0, y_0, ...),
/// blended by the shares.
void placeSide(const SideLayout& layout, const cv::Matx23d& toFrame, const Eigen::Ref<const Eigen::VectorXd>& e, bool mirrored,
               core::Shape68& shape);

/// Both sides of `shape` moved by the side net `net` (batch 2) in one call: each side's patch
/// (warpSide) into `patches` (reused), the net's answers placed (placeSide). A side whose
/// answer is not finite keeps its points.
void refineSides(const SideLayout& layout, nn::PatchNet& net, const cv::Mat& gray, std::array<cv::Mat, 2>& patches, core::Shape68& shape);

/// q above from the net's outputs d, g from this face alone (a still image).
core::Shape68 refinedLandmarks(const RefinerLayout& layout, const core::Similarity& toFrame, const Eigen::VectorXd& d,
                               const core::Shape68& lbf);

}  // namespace facetrack::refine
