#pragma once
// The part of the face model the fit looks at, in double precision.
//
// Of V(a, b) = neutral + B_id a + sum_j b_j D_j (face_model_data.hpp) the fit
// needs only the rows of the 68 landmark vertices and of the jaw-contour
// candidates, and only the expressions that move the landmarks. These rows
// are stored turned by R_0 = diag(1, -1, -1), the rotation that makes the
// model face the camera (model +y up and +z out of the face become camera -y
// and -z), so that a frontal head has rotation zero and the angle-axis
// parameters stay far from their singularity at pi.

#include "model/face_model_data.hpp"

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace facetrack::fit {

/// R_0 of the comment above.
Eigen::Matrix3d modelToFrontal();

struct FitBasis {
    /// Expressions the fit estimates, as indices into FaceModelData::expressions:
    /// those 68 landmarks can tell apart from the pose and from each other
    /// (observableExpressions in fit_basis.cpp). The others stay 0 here; the
    /// CNN stage estimates them from the face texture.
    std::vector<int> expressions;
    int native_expression_count = 0;

    /// Slot s holds model vertex vertices[s].
    std::vector<std::uint32_t> vertices;
    std::array<int, model::kLandmarkCount> landmark_slots{};
    /// For jaw landmarks 0..16, the slots of their contour candidates (own vertex first).
    std::array<std::vector<int>, model::kContourLandmarkCount> contour_slots;
    /// For each jaw landmark, the direction (frontal frame) its candidates sweep
    /// outwards: sideways (+-x) for the side landmarks, down (+y) for the chin
    /// (landmarks 6-10, whose candidates run under the chin).
    std::array<Eigen::Vector3d, model::kContourLandmarkCount> contour_outward;

    /// Row-major so that the three rows of one slot are contiguous.
    using Rows = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    Eigen::Matrix3Xd neutral;  ///< 3 x S, cm, frontal frame
    Rows identity;             ///< 3S x K, row 3s + c
    Rows expression;           ///< 3S x E, row 3s + c, columns in `expressions` order

    int slotCount() const { return static_cast<int>(vertices.size()); }
    int identityCount() const { return static_cast<int>(identity.cols()); }
    int expressionCount() const { return static_cast<int>(expression.cols()); }

    /// Names of the fitted expressions, in fit order.
    std::vector<std::string> expressionNames(const model::FaceModelData& data) const;
};

FitBasis buildFitBasis(const model::FaceModelData& data);

/// neutral + B_id a over the basis slots (3 x S): the shape the per-frame fit
/// deforms once identity is fixed.
Eigen::Matrix3Xd shapeWithIdentity(const FitBasis& basis, const Eigen::VectorXd& identity);

}  // namespace facetrack::fit
