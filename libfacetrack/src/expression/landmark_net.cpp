#include "expression/landmark_net.hpp"

#include "model/internals.hpp"

namespace facetrack::expression {

fit::FitBasis landmarkBasis(const FaceModel& model, const std::vector<int>& expressions) {
    fit::FitBasis basis = fit::buildFitBasis(model::dataOf(model), expressions);
    if (const model::LandmarkConvention* convention = model::Internals::convention(model)) {
        fit::applyConvention(basis, *convention, model::dataOf(model));
    }
    return basis;
}

Eigen::Matrix2d patchToFrame(const WarpLayout& layout, const Eigen::Matrix2Xd& anchors) {
    const Eigen::Matrix<double, 3, 2> affine = layout.affine_solve * anchors.transpose();
    return affine.topRows<2>().transpose();
}

fit::Landmarks2d projectedLandmarks(const fit::FitBasis& basis, const Eigen::Matrix3Xd& identityShape, const core::Camera& camera,
                                    const fit::FaceParams& params, Eigen::Matrix3Xd& slots) {
    fit::slotPositions(basis, identityShape, params.expression, slots);
    return fit::projectSlots(basis, slots, camera, params.pose, fit::silhouetteContourAt(basis, slots, camera, params.pose));
}

Eigen::VectorXd displacementsOf(const Eigen::Matrix2d& patchToFrame, const fit::Landmarks2d& projected, const fit::Landmarks2d& q) {
    const fit::Landmarks2d d = patchToFrame.inverse() * (q - projected);
    return Eigen::Map<const Eigen::VectorXd>(d.data(), kLandmarkOutputs);
}

fit::Landmarks2d displaced(const Eigen::Matrix2d& patchToFrame, const fit::Landmarks2d& projected, const Eigen::VectorXd& d) {
    return projected + patchToFrame * Eigen::Map<const fit::Landmarks2d>(d.data());
}

}  // namespace facetrack::expression
