#pragma once
// The expression stage's lip net: 40 lip points of MediaPipe Face Landmarker's mesh, read from a
// mouth patch, for the geometry net (geometry_net.hpp). That model's blendshapes, the teacher the
// stage learns from, are read off its mesh; the 68 points have 20 on the lips and miss most of a
// pucker, a funnel or a rolled lip (docs/cnn.md). Trained by tools/train/expression/train_lips.py.
//
// The patch: with the 68 points' normalising frame (centre c, angle theta, size s; geometry_net.hpp)
// and the anchor a = (0, mean normalised y of points 48-67), patch pixel u (0-based) shows
//     p(u) = c + s R(theta) (a + H ((2 u + 1) / S - 1)),
// S the patch's side in pixels and H its half-width in normalised units, bilinear, borders
// replicated. The net regresses each lip point's (q - a) / H, q its normalised position, and reads
// the patch and its mirror image in one call:
//     l = a + H (n(P) + M n(mirror P)) / 2,
// M the mirror's renumbering (kLipMirror) with x negated.

#include "core/shape2d.hpp"
#include "expression/geometry_net.hpp"
#include "nn/patch_net.hpp"

#include <opencv2/core.hpp>

#include <array>
#include <string>

namespace facetrack::expression {

/// Lip point k of a mirror image is point kLipMirror[k] of the face, x negated: the outer line's 20
/// points from one corner round, then the inner line's 20 (train_lips.py: LIPS).
extern const std::array<int, nn::kLipPoints> kLipMirror;

/// The lips of the mirror image, in its normalised frame (which is the face's, mirrored).
LipPoints mirroredLips(const LipPoints& lips);

/// The mouth patch of a face: the 2 x 3 map from patch pixels to frame pixels, p(u) above, and a.
struct MouthPatch {
    cv::Matx23d to_frame;
    Eigen::Vector2f anchor;
};
MouthPatch mouthPatch(const core::Shape68& points, int size, float half);

class LipNet {
public:
    /// `onnx`: a net of batch 2 from size x size patches to 2 nn::kLipPoints values each; `what`
    /// names it in errors. Throws Error when it does not load.
    LipNet(const std::string& onnx, int size, float half, const std::string& what);

    /// l above for the face of `points` in `gray` (8-bit). Not thread-safe (keeps its buffers).
    const LipPoints& predict(const cv::Mat& gray, const core::Shape68& points);

    const char* engineName() const { return net_.engineName(); }

private:
    nn::PatchNet net_;
    int size_;
    float half_;
    std::array<cv::Mat, 2> patches_;
    LipPoints lips_;
};

}  // namespace facetrack::expression
