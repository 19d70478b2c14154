#pragma once
// The part of the face model the fit looks at, in double precision.
//
// Of V(a, b) = neutral + B_id a + sum_j b_j D_j (face_model_data.hpp) the fit
// needs only the rows of the 68 landmark vertices and of the jaw-contour
// candidates, and only the expressions that move the landmarks (the dense
// teacher fit, tools/data/dense, uses the rows of other surface points). These rows
// are stored turned by R_0 = diag(1, -1, -1), the rotation that makes the
// model face the camera (model +y up and +z out of the face become camera -y
// and -z), so that a frontal head has rotation zero and the angle-axis
// parameters stay far from their singularity at pi.

#include "facetrack/face_model.hpp"
#include "model/face_model_data.hpp"
#include "model/landmark_convention.hpp"

#include <Eigen/Core>

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace facetrack::fit {

/// A native expression's mirror partner ("mouthSmile_L" <-> "mouthSmile_R",
/// "jawLeft" <-> "jawRight"), or "" for an unsided one.
std::string mirrorName(const std::string& name);

/// R_0 of the comment above.
Eigen::Matrix3d modelToFrontal();

/// A point on the model's surface: sum_k weights_k V(vertices_k), barycentric
/// in a triangle (a vertex is the point (v, v, v) with weights (1, 0, 0)).
struct SurfacePoint {
    std::array<std::uint32_t, 3> vertices{};
    Eigen::Vector3d weights = Eigen::Vector3d::UnitX();
};

/// The rows of V(a, b) for a set of surface points ("slots"), turned by R_0.
struct PointBasis {
    /// Expressions fitted, as indices into FaceModelData::expressions. For the
    /// landmark fit: those 68 landmarks can tell apart from the pose and from each
    /// other (observableExpressions). The others stay 0 here.
    std::vector<int> expressions;
    int native_expression_count = 0;

    /// Row-major so that the three rows of one slot are contiguous.
    using Rows = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    Eigen::Matrix3Xd neutral;  ///< 3 x S, cm, frontal frame
    Rows identity;             ///< 3S x K, row 3s + c
    Rows expression;           ///< 3S x E, row 3s + c, columns in `expressions` order

    int slotCount() const { return static_cast<int>(neutral.cols()); }
    int identityCount() const { return static_cast<int>(identity.cols()); }
    int expressionCount() const { return static_cast<int>(expression.cols()); }

    /// Names of the fitted expressions, in fit order.
    std::vector<std::string> expressionNames(const model::FaceModelData& data) const;
};

/// The basis of `points` (slot s = points[s]) for the expressions `expressions`.
PointBasis buildPointBasis(const model::FaceModelData& data, const std::vector<SurfacePoint>& points, const std::vector<int>& expressions);

/// The expressions that the image motion of `points` can tell apart from the
/// pose and from each other (the rule in fit_basis.cpp), eyeLook* excluded
/// (eyeball rotation belongs to the gaze stage). Indices into data.expressions.
std::vector<int> observableExpressions(const model::FaceModelData& data, const std::vector<SurfacePoint>& points);

/// The distinct motion of each of `expressions` (eye-corner distances per unit
/// weight) among them and the pose: what that rule compares with its threshold.
std::vector<double> distinctMotion(const model::FaceModelData& data, const std::vector<SurfacePoint>& points,
                                   const std::vector<int>& expressions);

/// The landmark fit's basis: slots are the 68 landmark vertices and the jaw's
/// contour candidates.
struct FitBasis : PointBasis {
    /// Slot s holds model vertex vertices[s].
    std::vector<std::uint32_t> vertices;
    std::array<int, model::kLandmarkCount> landmark_slots{};
    /// For jaw landmarks 0..16, the slots of their contour candidates (own vertex first).
    std::array<std::vector<int>, model::kContourLandmarkCount> contour_slots;
    /// For each jaw landmark, the direction (frontal frame) its candidates sweep
    /// outwards: sideways (+-x) for the side landmarks, down (+y) for the chin
    /// (landmarks 6-10, whose candidates run under the chin).
    std::array<Eigen::Vector3d, model::kContourLandmarkCount> contour_outward;
    /// Per fitted expression, the factor on the fit's w_l2: the learned prior
    /// (landmark_convention.hpp). All 1 without one.
    Eigen::VectorXd expression_prior;

    /// w_l2 times expression_prior: the weight of each b_j^2.
    Eigen::VectorXd expressionPriorWeights(double l2) const;
};

/// With the expressions the 68 landmarks observe (observableExpressions).
FitBasis buildFitBasis(const model::FaceModelData& data);
/// With `expressions` (indices into data.expressions), e.g. to project the
/// landmarks of a face whose other expressions are known (expression/landmark_net.hpp).
FitBasis buildFitBasis(const model::FaceModelData& data, const std::vector<int>& expressions);

/// Moves the basis's landmark slots by the convention's offsets and sets its
/// expression prior (names from `data`).
void applyConvention(FitBasis& basis, const model::LandmarkConvention& convention, const model::FaceModelData& data);

/// The fit's basis of `face`: buildFitBasis with the face model's landmark
/// convention applied. Built once per face model and shared by every fit of it
/// (a cache that holds it while the face model lives). Thread-safe.
std::shared_ptr<const FitBasis> basisOf(const std::shared_ptr<const FaceModel>& face);

/// neutral + B_id a over the basis slots (3 x S): the shape the per-frame fit
/// deforms once identity is fixed.
Eigen::Matrix3Xd shapeWithIdentity(const PointBasis& basis, const Eigen::VectorXd& identity);

}  // namespace facetrack::fit
