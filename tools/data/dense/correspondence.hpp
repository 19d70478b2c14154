#pragma once
// Where MediaPipe's 468 mesh vertices lie on the face model's surface.
//
// The canonical neutral mesh C (MediaPipe) and the model's neutral V(a, 0)
// share their axes (+y up, +z out of the face) but not scale, origin or
// identity. Iterated closest points with a similarity and the identity:
//   min_{s, R, t, a}  sum_i |s R C_i + t - P_i(a)|^2 + lambda |a|^2,
// P_i(a) the point of the model's face surface nearest s R C_i + t, the
// identity a moving the surface towards the canonical face. Each vertex's
// final nearest point, as barycentric weights in a model triangle, plus the
// remaining offset o_i = s R C_i + t - P_i(a) (mostly along the normal), is
// its correspondence: the point sits at sum_k w_ik V(v_ik) + o_i for every
// identity and expression, so the canonical face is reproduced exactly (like
// the landmark convention, it absorbs where MediaPipe's points sit off the model).

#include "fit/fit_basis.hpp"
#include "model/face_model_data.hpp"

#include <Eigen/Core>

#include <vector>

namespace facetrack::dense {

struct Correspondence {
    std::vector<fit::SurfacePoint> points;  ///< per MediaPipe vertex
    std::vector<double> distance_cm;        ///< from the aligned canonical vertex to its surface point
    Eigen::Matrix3Xd offsets_cm;            ///< o_i, model frame
    std::vector<bool> usable;               ///< distance below kMaxDistanceCm: the fit uses it
    double scale = 1.0;                     ///< s
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    Eigen::Vector3d translation = Eigen::Vector3d::Zero();
    Eigen::VectorXd identity;  ///< a, of the canonical face
    int usableCount() const;
    /// The MediaPipe vertex ids the fit uses.
    std::vector<int> usableVertices() const;
};

/// A canonical vertex further than this from the model's face surface has no
/// counterpart there (the canonical mesh reaches past the model's face region
/// or into the mouth): it is left out.
constexpr double kMaxDistanceCm = 0.4;

/// The nearest point of triangle (a, b, c) to p, as barycentric weights.
Eigen::Vector3d closestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// MediaPipe's vertices at the outer eye corners (subject's right, left).
constexpr int kCanonicalEyeCorners[2] = {33, 263};

/// canonical: 3 x 468, MediaPipe's frame (cm). `iterations` rounds of closest points.
Correspondence buildCorrespondence(const model::FaceModelData& data, const Eigen::Matrix3Xd& canonical, int iterations = 30);

}  // namespace facetrack::dense
