#include "fit/fit_basis.hpp"

#include "facetrack/error.hpp"
#include "model/internals.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <map>
#include <mutex>

namespace facetrack::fit {

namespace {

/// A fitted expression must move the landmarks, per unit weight, by at least
/// this much (in eye-corner distances) in a direction that neither the pose nor
/// the other fitted expressions can produce. Below that, 1-2 px of landmark
/// noise on a 90 px face moves the weight by more than ~0.2.
constexpr double kMinDistinctMotion = 0.08;

}  // namespace

// The mirror partner's name ("mouthSmile_L" <-> "mouthSmile_R",
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

Eigen::Matrix3d modelToFrontal() { return Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal(); }

std::vector<std::string> PointBasis::expressionNames(const model::FaceModelData& data) const {
    std::vector<std::string> names;
    for (const int e : expressions) names.push_back(data.expressions[e].name);
    return names;
}

// The observability rule. J holds, for a frontal face seen orthographically,
// the image-plane motion of the points (in eye-corner distances) under 6 pose
// directions (tx, ty, scale, three rotations) and under each expression. The
// distinct motion of column j within J is 1 / sqrt((J^T J)^{-1}_jj), its
// distance from the span of the others. Repeatedly drop the least distinct
// expression, with its mirror partner, until every remaining one reaches
// kMinDistinctMotion.
namespace {

/// J of the comment above for all expressions (columns 6.. are data.expressions).
Eigen::MatrixXd motionMatrix(const model::FaceModelData& data, const std::vector<SurfacePoint>& points) {
    const auto& lm = data.landmark_vertices;
    const double eyes = (data.neutral.col(lm[36]) - data.neutral.col(lm[45])).norm();
    std::vector<int> all_expressions(data.expressions.size());
    for (std::size_t e = 0; e < all_expressions.size(); ++e) all_expressions[e] = static_cast<int>(e);
    const PointBasis rows = buildPointBasis(data, points, all_expressions);
    constexpr int kPose = 6;
    const auto n = static_cast<Eigen::Index>(points.size());
    Eigen::MatrixXd all(2 * n, kPose + rows.expressionCount());
    for (Eigen::Index i = 0; i < n; ++i) {
        // The frontal frame's y is the model's -y: that flips only signs, not distinctness.
        const Eigen::Vector3d x = rows.neutral.col(i) / eyes;
        all.block<2, kPose>(2 * i, 0) << 1, 0, x.x(), 0, x.z(), -x.y(),  //
            0, 1, x.y(), -x.z(), 0, x.x();
        all.block(2 * i, kPose, 2, rows.expressionCount()) = rows.expression.middleRows<2>(3 * i) / eyes;
    }
    return all;
}

/// 1 / sqrt((J^T J)^{-1}_jj) for the columns of `kept`, with the pose.
Eigen::VectorXd distinctMotionOf(const Eigen::MatrixXd& all, const std::vector<int>& kept) {
    constexpr int kPose = 6;
    Eigen::MatrixXd j(all.rows(), kPose + static_cast<Eigen::Index>(kept.size()));
    j.leftCols(kPose) = all.leftCols(kPose);
    for (std::size_t k = 0; k < kept.size(); ++k) j.col(kPose + static_cast<Eigen::Index>(k)) = all.col(kPose + kept[k]);
    const Eigen::MatrixXd gram = j.transpose() * j + 1e-12 * Eigen::MatrixXd::Identity(j.cols(), j.cols());
    const Eigen::VectorXd inverseDiagonal = gram.ldlt().solve(Eigen::MatrixXd::Identity(j.cols(), j.cols())).diagonal();
    return inverseDiagonal.tail(static_cast<Eigen::Index>(kept.size())).cwiseSqrt().cwiseInverse();
}

}  // namespace

std::vector<int> observableExpressions(const model::FaceModelData& data, const std::vector<SurfacePoint>& points) {
    std::vector<int> kept;
    for (int e = 0; e < static_cast<int>(data.expressions.size()); ++e) {
        if (data.expressions[e].name.rfind("eyeLook", 0) != 0) kept.push_back(e);
    }
    const Eigen::MatrixXd all = motionMatrix(data, points);
    while (!kept.empty()) {
        Eigen::Index worst = 0;
        if (distinctMotionOf(all, kept).minCoeff(&worst) >= kMinDistinctMotion) break;
        const std::string partner = mirrorName(data.expressions[kept[worst]].name);
        kept.erase(kept.begin() + worst);
        std::erase_if(kept, [&](int e) { return !partner.empty() && data.expressions[e].name == partner; });
    }
    return kept;
}

std::vector<double> distinctMotion(const model::FaceModelData& data, const std::vector<SurfacePoint>& points,
                                   const std::vector<int>& expressions) {
    const Eigen::VectorXd d = distinctMotionOf(motionMatrix(data, points), expressions);
    return {d.data(), d.data() + d.size()};
}

PointBasis buildPointBasis(const model::FaceModelData& data, const std::vector<SurfacePoint>& points, const std::vector<int>& expressions) {
    PointBasis b;
    b.native_expression_count = static_cast<int>(data.expressions.size());
    b.expressions = expressions;
    const auto slots = static_cast<Eigen::Index>(points.size());
    const Eigen::Matrix3d r0 = modelToFrontal();
    b.neutral.setZero(3, slots);
    b.identity.setZero(3 * slots, data.identityCount());
    b.expression.setZero(3 * slots, static_cast<Eigen::Index>(expressions.size()));
    for (Eigen::Index s = 0; s < slots; ++s) {
        const SurfacePoint& p = points[static_cast<std::size_t>(s)];
        for (int c = 0; c < 3; ++c) {
            const std::uint32_t v = p.vertices[c];
            const double w = p.weights[c];
            if (w == 0.0) continue;
            b.neutral.col(s) += w * (r0 * data.neutral.col(v).cast<double>());
            b.identity.middleRows<3>(3 * s) += w * (r0 * data.identity_basis.middleRows<3>(3 * v).cast<double>());
            for (std::size_t k = 0; k < expressions.size(); ++k) {
                const auto& shape = data.expressions[static_cast<std::size_t>(expressions[k])];
                const auto it = std::lower_bound(shape.vertices.begin(), shape.vertices.end(), v);
                if (it == shape.vertices.end() || *it != v) continue;
                b.expression.block<3, 1>(
                    3 * s, static_cast<Eigen::Index>(k)) += w * (r0 * shape.deltas.col(it - shape.vertices.begin()).cast<double>());
            }
        }
    }
    return b;
}

FitBasis buildFitBasis(const model::FaceModelData& data) {
    std::vector<SurfacePoint> landmarks(model::kLandmarkCount);
    for (int i = 0; i < model::kLandmarkCount; ++i) landmarks[i].vertices.fill(data.landmark_vertices[i]);
    return buildFitBasis(data, observableExpressions(data, landmarks));
}

FitBasis buildFitBasis(const model::FaceModelData& data, const std::vector<int>& expressions) {
    const auto& lm = data.landmark_vertices;
    std::vector<std::uint32_t> vertices;
    std::array<int, model::kLandmarkCount> landmark_slots{};
    std::array<std::vector<int>, model::kContourLandmarkCount> contour_slots;
    std::map<std::uint32_t, int> slotOf;
    auto slot = [&](std::uint32_t v) {
        const auto [it, added] = slotOf.emplace(v, static_cast<int>(vertices.size()));
        if (added) vertices.push_back(v);
        return it->second;
    };
    for (int i = 0; i < model::kLandmarkCount; ++i) landmark_slots[i] = slot(lm[i]);
    for (int i = 0; i < model::kContourLandmarkCount; ++i) {
        for (const std::uint32_t v : data.contour_candidates[i]) contour_slots[i].push_back(slot(v));
    }
    std::vector<SurfacePoint> points(vertices.size());
    for (std::size_t s = 0; s < vertices.size(); ++s) points[s].vertices = {vertices[s], vertices[s], vertices[s]};

    FitBasis b;
    static_cast<PointBasis&>(b) = buildPointBasis(data, points, expressions);
    b.vertices = std::move(vertices);
    b.landmark_slots = landmark_slots;
    b.contour_slots = std::move(contour_slots);
    b.expression_prior = Eigen::VectorXd::Ones(b.expressionCount());
    for (int i = 0; i < model::kContourLandmarkCount; ++i) {
        const bool chin = i >= 6 && i <= 10;
        const double side = b.neutral(0, b.landmark_slots[i]) < 0.0 ? -1.0 : 1.0;
        b.contour_outward[i] = chin ? Eigen::Vector3d::UnitY() : Eigen::Vector3d(side, 0.0, 0.0);
    }
    return b;
}

Eigen::VectorXd FitBasis::expressionPriorWeights(double l2) const {
    return expression_prior.size() == expressionCount() ? Eigen::VectorXd(l2 * expression_prior)
                                                        : Eigen::VectorXd::Constant(expressionCount(), l2);
}

Eigen::Matrix3Xd shapeWithIdentity(const PointBasis& basis, const Eigen::VectorXd& identity) {
    Eigen::Matrix3Xd shape = basis.neutral;
    if (identity.size() == 0) return shape;
    const Eigen::VectorXd offsets = basis.identity * identity;
    shape += Eigen::Map<const Eigen::Matrix3Xd>(offsets.data(), 3, basis.slotCount());
    return shape;
}

void applyConvention(FitBasis& basis, const model::LandmarkConvention& c, const model::FaceModelData& data) {
    for (int i = 0; i < model::kLandmarkCount; ++i)
        basis.neutral.col(basis.landmark_slots[static_cast<std::size_t>(i)]) += c.offsets_frontal_cm.col(i);
    const auto names = basis.expressionNames(data);
    basis.expression_prior = Eigen::VectorXd::Ones(basis.expressionCount());
    for (std::size_t k = 0; k < names.size(); ++k) {
        const auto it = c.expression_prior.find(names[k]);
        if (it != c.expression_prior.end()) basis.expression_prior[static_cast<Eigen::Index>(k)] = it->second;
    }
}

std::shared_ptr<const FitBasis> basisOf(const std::shared_ptr<const FaceModel>& face) {
    if (!face) throw Error("fit: no face model given");
    struct Entry {
        std::weak_ptr<const FaceModel> face;
        std::shared_ptr<const FitBasis> basis;
    };
    static std::mutex mutex;
    static std::vector<Entry> cache;
    const std::lock_guard<std::mutex> lock(mutex);
    cache.erase(std::remove_if(cache.begin(), cache.end(), [](const Entry& e) { return e.face.expired(); }), cache.end());
    for (const Entry& e : cache) {
        if (!e.face.owner_before(face) && !face.owner_before(e.face)) return e.basis;
    }
    const model::FaceModelData& data = model::dataOf(*face);
    FitBasis basis = buildFitBasis(data);
    if (const model::LandmarkConvention* convention = model::Internals::convention(*face)) applyConvention(basis, *convention, data);
    cache.push_back({face, std::make_shared<const FitBasis>(std::move(basis))});
    return cache.back().basis;
}

}  // namespace facetrack::fit
