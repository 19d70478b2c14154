#pragma once
// The expression stage's geometry net: the expressions as the landmarks' shape shows them.
//
// MediaPipe's blendshapes, the teacher the stage learns from, are read off a face mesh's points;
// from the 68 points alone a small net follows the teacher's brows, lid squint and lip press on
// people it was not trained on (Pearson r 0.7-0.9) where the texture net reads 0.2-0.7
// (docs/cnn.md). Trained by tools/train/expression/train_geometry.py.
//
// Features f (nn::kGeometryFeatures): the points p_i centred on their mean c, rotated by R(-theta),
// theta the angle of the line from the right eye's centre (mean of points 36-41) to the left's
// (42-47), and scaled to unit root-mean-square distance s from c:
//     q_i = R(-theta) (p_i - c) / s,   f = (q_0x, q_0y, ..., q_67x, q_67y, sin(pitch), sin(yaw)),
// so a face moved, scaled or rolled in the image gives the same features. The net: dense layers,
// ReLU between them, a sigmoid after the last. Read mirror-averaged, as the texture nets are:
//     w = (g(f) + M g(f_mirror)) / 2,
// f_mirror the features of the mirror image (points x-negated and renumbered by kMirror68, yaw
// negated) and M the swap of each left expression with its right one. With a lip net (lip_net.hpp)
// f goes on with the 40 lip points in the same frame, (l_0x, l_0y, ..., l_39x, l_39y); the mirror
// image's are x-negated and renumbered by kLipMirror.

#include "core/shape2d.hpp"
#include "nn/cnn_model_data.hpp"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace facetrack::expression {

using GeometryFeatures = Eigen::Matrix<float, nn::kGeometryFeatures, 1>;
/// Lip points in the normalised frame below, one a column.
using LipPoints = Eigen::Matrix<float, 2, nn::kLipPoints>;

/// The frame the features are in: q = R(-theta) (p - centre) / rms.
struct NormalisingFrame {
    Eigen::Vector2f centre;
    float theta = 0.f;
    float rms = 1.f;
    Eigen::Matrix2f unroll() const;  ///< R(-theta)
};
NormalisingFrame normalisingFrame(const core::Shape68& points);

/// f above, from the points (pixels) and the head's pitch and yaw (degrees, HeadPose::euler_deg).
GeometryFeatures geometryFeatures(const core::Shape68& points, double pitchDeg, double yawDeg);

/// f of the face's mirror image.
GeometryFeatures mirroredGeometryFeatures(const core::Shape68& points, double pitchDeg, double yawDeg);

class GeometryNet {
public:
    /// `expressions`: the net's outputs (native names), each sided one's partner among them. A net
    /// whose first layer reads 2 nn::kLipPoints more inputs than nn::kGeometryFeatures reads lips.
    /// Throws Error when a sided expression has no partner.
    GeometryNet(std::vector<nn::DenseLayer> layers, const std::vector<std::string>& expressions);

    bool readsLips() const { return reads_lips_; }
    /// w above, one value in [0, 1] per expression; `lips` (required when readsLips()) in the
    /// points' normalised frame. Not thread-safe (keeps its buffers): one per stage.
    const Eigen::VectorXf& predict(const core::Shape68& points, double pitchDeg, double yawDeg, const LipPoints* lips = nullptr);
    /// g(f): one pass, without the mirror image; f of the first layer's size.
    const Eigen::VectorXf& forward(const Eigen::VectorXf& f);

private:
    std::vector<Eigen::MatrixXf> weights_;
    std::vector<Eigen::VectorXf> biases_;
    std::vector<int> mirror_;  ///< output k of the mirror image is output mirror_[k] of the face
    bool reads_lips_ = false;
    Eigen::VectorXf input_;
    std::vector<Eigen::VectorXf> activations_;
    Eigen::VectorXf direct_, averaged_;
};

}  // namespace facetrack::expression
