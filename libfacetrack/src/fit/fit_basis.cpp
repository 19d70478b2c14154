#include "fit/fit_basis.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <map>

namespace facetrack::fit {

namespace {

/// A fitted expression must move the landmarks, per unit weight, by at least
/// this much (in eye-corner distances) in a direction that neither the pose nor
/// the other fitted expressions can produce. Below that, 1-2 px of landmark
/// noise on a 90 px face moves the weight by more than ~0.2.
constexpr double kMinDistinctMotion = 0.08;

/// The mirror partner's name ("mouthSmile_L" <-> "mouthSmile_R",
/// "jawLeft" <-> "jawRight"), or "".
std::string mirrorName(const std::string& name) {
    auto swapSuffix = [&](const std::string& a, const std::string& b) -> std::string {
        if (name.size() > a.size() && name.compare(name.size() - a.size(), a.size(), a) == 0) {
            return name.substr(0, name.size() - a.size()) + b;
        }
        return "";
    };
    for (const auto& [a, b] : {std::pair{"_L", "_R"}, {"_R", "_L"}, {"Left", "Right"}, {"Right", "Left"}}) {
        if (auto partner = swapSuffix(a, b); !partner.empty()) return partner;
    }
    return "";
}

/// The observable expressions. J holds, for a frontal face seen
/// orthographically, the image-plane landmark motion (in eye-corner
/// distances) of 6 pose directions (tx, ty, scale, three rotations) and of
/// each expression. The distinct motion of column j within J is
/// 1 / sqrt((J^T J)^{-1}_jj), its distance from the span of the others.
/// Repeatedly drop the least distinct expression, with its mirror partner,
/// until every remaining one reaches kMinDistinctMotion.
std::vector<int> observableExpressions(const model::FaceModelData& data) {
    const auto& lm = data.landmark_vertices;
    const double eyes = (data.neutral.col(lm[36]) - data.neutral.col(lm[45])).norm();
    std::vector<int> kept;
    for (int e = 0; e < static_cast<int>(data.expressions.size()); ++e) {
        // Eyeball rotation belongs to the gaze stage.
        if (data.expressions[e].name.rfind("eyeLook", 0) != 0) kept.push_back(e);
    }
    constexpr int kPose = 6;
    Eigen::MatrixXd all(2 * model::kLandmarkCount, kPose + data.expressions.size());
    all.setZero();
    for (int i = 0; i < model::kLandmarkCount; ++i) {
        const Eigen::Vector3d x = data.neutral.col(lm[i]).cast<double>() / eyes;
        all.block<2, kPose>(2 * i, 0) << 1, 0, x.x(), 0, x.z(), -x.y(),  //
            0, 1, x.y(), -x.z(), 0, x.x();
        for (std::size_t e = 0; e < data.expressions.size(); ++e) {
            const auto& shape = data.expressions[e];
            const auto it = std::lower_bound(shape.vertices.begin(), shape.vertices.end(), lm[i]);
            if (it == shape.vertices.end() || *it != lm[i]) continue;
            all.block<2, 1>(2 * i, kPose + e) = shape.deltas.col(it - shape.vertices.begin()).head<2>().cast<double>() / eyes;
        }
    }
    while (!kept.empty()) {
        Eigen::MatrixXd j(all.rows(), kPose + kept.size());
        j.leftCols(kPose) = all.leftCols(kPose);
        for (std::size_t k = 0; k < kept.size(); ++k) j.col(kPose + k) = all.col(kPose + kept[k]);
        const Eigen::MatrixXd gram = j.transpose() * j + 1e-12 * Eigen::MatrixXd::Identity(j.cols(), j.cols());
        const Eigen::VectorXd inverseDiagonal = gram.ldlt().solve(Eigen::MatrixXd::Identity(j.cols(), j.cols())).diagonal();
        Eigen::Index worst = 0;
        const double largest = inverseDiagonal.tail(kept.size()).maxCoeff(&worst);
        if (1.0 / std::sqrt(largest) >= kMinDistinctMotion) break;
        const std::string partner = mirrorName(data.expressions[kept[worst]].name);
        kept.erase(kept.begin() + worst);
        std::erase_if(kept, [&](int e) { return !partner.empty() && data.expressions[e].name == partner; });
    }
    return kept;
}

}  // namespace

Eigen::Matrix3d modelToFrontal() { return Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal(); }

std::vector<std::string> FitBasis::expressionNames(const model::FaceModelData& data) const {
    std::vector<std::string> names;
    for (const int e : expressions) names.push_back(data.expressions[e].name);
    return names;
}

FitBasis buildFitBasis(const model::FaceModelData& data) {
    FitBasis b;
    b.native_expression_count = static_cast<int>(data.expressions.size());
    const auto& lm = data.landmark_vertices;
    b.expressions = observableExpressions(data);

    std::map<std::uint32_t, int> slotOf;
    auto slot = [&](std::uint32_t v) {
        const auto [it, added] = slotOf.emplace(v, static_cast<int>(b.vertices.size()));
        if (added) b.vertices.push_back(v);
        return it->second;
    };
    for (int i = 0; i < model::kLandmarkCount; ++i) b.landmark_slots[i] = slot(lm[i]);
    for (int i = 0; i < model::kContourLandmarkCount; ++i) {
        for (const std::uint32_t v : data.contour_candidates[i]) b.contour_slots[i].push_back(slot(v));
    }

    const int slots = b.slotCount();
    const Eigen::Matrix3d r0 = modelToFrontal();
    b.neutral.resize(3, slots);
    b.identity.resize(3 * slots, data.identityCount());
    b.expression.setZero(3 * slots, static_cast<Eigen::Index>(b.expressions.size()));
    for (int s = 0; s < slots; ++s) {
        const std::uint32_t v = b.vertices[s];
        b.neutral.col(s) = r0 * data.neutral.col(v).cast<double>();
        b.identity.middleRows<3>(3 * s) = r0 * data.identity_basis.middleRows<3>(3 * v).cast<double>();
        for (std::size_t k = 0; k < b.expressions.size(); ++k) {
            const auto& shape = data.expressions[b.expressions[k]];
            const auto it = std::lower_bound(shape.vertices.begin(), shape.vertices.end(), v);
            if (it == shape.vertices.end() || *it != v) continue;
            b.expression.block<3, 1>(3 * s, k) = r0 * shape.deltas.col(it - shape.vertices.begin()).cast<double>();
        }
    }
    for (int i = 0; i < model::kContourLandmarkCount; ++i) {
        const bool chin = i >= 6 && i <= 10;
        const double side = b.neutral(0, b.landmark_slots[i]) < 0.0 ? -1.0 : 1.0;
        b.contour_outward[i] = chin ? Eigen::Vector3d::UnitY() : Eigen::Vector3d(side, 0.0, 0.0);
    }
    return b;
}

Eigen::Matrix3Xd shapeWithIdentity(const FitBasis& basis, const Eigen::VectorXd& identity) {
    Eigen::Matrix3Xd shape = basis.neutral;
    if (identity.size() == 0) return shape;
    const Eigen::VectorXd offsets = basis.identity * identity;
    shape += Eigen::Map<const Eigen::Matrix3Xd>(offsets.data(), 3, basis.slotCount());
    return shape;
}

}  // namespace facetrack::fit
