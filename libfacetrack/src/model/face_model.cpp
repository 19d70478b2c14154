#include "facetrack/face_model.hpp"

#include "facetrack/error.hpp"
#include "facetrack/version.hpp"
#include "model/arkit_mapping.hpp"
#include "model/face_model_data.hpp"
#include "model/internals.hpp"
#include "model/landmark_convention.hpp"

#include <algorithm>
#include <filesystem>

namespace facetrack {

FaceModel::FaceModel(std::shared_ptr<const model::FaceModelData> data, std::string source, std::string convention)
    : data_(std::move(data)), source_(std::move(source)), convention_(std::move(convention)) {
    if (!data_) throw Error("FaceModel: null model data");
    for (const auto& e : data_->expressions) expression_names_.push_back(e.name);
    arkit_ = std::make_shared<const model::ArkitMapping>(model::makeArkitMapping(expression_names_));
    landmark_offsets_mm_.assign(model::kLandmarkCount, Vec3{0.f, 0.f, 0.f});
    if (!convention_.empty()) {
        landmark_convention_ = std::make_shared<const model::LandmarkConvention>(model::readLandmarkConvention(convention_));
        const model::LandmarkConvention& convention = *landmark_convention_;
        // Frontal frame (cm) to model frame (mm): R_0 = diag(1, -1, -1) (fit_basis.hpp).
        for (int i = 0; i < model::kLandmarkCount; ++i) {
            const auto o = convention.offsets_frontal_cm.col(i);
            landmark_offsets_mm_[static_cast<std::size_t>(i)] = {static_cast<float>(10.0 * o.x()), static_cast<float>(-10.0 * o.y()),
                                                                 static_cast<float>(-10.0 * o.z())};
        }
    }
}

std::shared_ptr<const FaceModel> FaceModel::load(const std::string& path) {
    return model::Internals::make(model::readFaceModel(path), path);
}

std::shared_ptr<const FaceModel> FaceModel::load(const std::string& path, const std::string& conventionPath) {
    return model::Internals::make(model::readFaceModel(path), path, conventionPath);
}

std::shared_ptr<const FaceModel> FaceModel::loadDefault() {
    const std::string convention = defaultConventionPath();
    std::error_code ec;
    return std::filesystem::exists(convention, ec) ? load(defaultPath(), convention) : load(defaultPath());
}
std::string FaceModel::defaultPath() { return modelDirectory() + "/face_model.ftm"; }
std::string FaceModel::defaultConventionPath() { return modelDirectory() + "/landmark_convention.ftm"; }
const std::string& FaceModel::conventionPath() const { return convention_; }

std::uint32_t FaceModel::formatVersion() { return model::kFaceModelVersion; }

int FaceModel::vertexCount() const { return data_->vertexCount(); }
int FaceModel::triangleCount() const { return static_cast<int>(data_->triangles.size()); }
int FaceModel::identityCount() const { return data_->identityCount(); }
float FaceModel::identityExplainedVariance() const { return data_->identity_explained_variance; }
const std::vector<std::string>& FaceModel::expressionNames() const { return expression_names_; }
const std::string& FaceModel::sourcePath() const { return source_; }

std::array<float, kArkitBlendshapeCount> FaceModel::toArkit(const std::vector<float>& native) const {
    if (native.size() != expression_names_.size()) {
        throw Error("toArkit: " + std::to_string(native.size()) + " weights given, the model has " +
                    std::to_string(expression_names_.size()) + " expressions");
    }
    return model::toArkit(*arkit_, native);
}

std::vector<int> FaceModel::landmarkVertices() const {
    return std::vector<int>(data_->landmark_vertices.begin(), data_->landmark_vertices.end());
}

std::vector<Vec3> FaceModel::landmarkPoints(const std::vector<Vec3>& mesh) const {
    if (static_cast<int>(mesh.size()) != vertexCount())
        throw Error("FaceModel::landmarkPoints: a mesh of " + std::to_string(mesh.size()) + " vertices given, the model has " +
                    std::to_string(vertexCount()));
    std::vector<Vec3> out(model::kLandmarkCount);
    for (std::size_t i = 0; i < out.size(); ++i) {
        const Vec3& v = mesh[data_->landmark_vertices[i]];
        const Vec3& o = landmark_offsets_mm_[i];
        out[i] = {v.x + o.x, v.y + o.y, v.z + o.z};
    }
    return out;
}

std::vector<Vec3> FaceModel::vertices(const std::vector<float>& identity, const std::vector<float>& expression) const {
    std::vector<Vec3> out;
    vertices(identity, expression, out);
    return out;
}

namespace {

void checkCoefficients(const model::FaceModelData& d, const std::vector<float>& identity, const std::vector<float>& expression) {
    if (!identity.empty() && static_cast<int>(identity.size()) != d.identityCount()) {
        throw Error("FaceModel::vertices: " + std::to_string(identity.size()) + " identity coefficients given, the model has " +
                    std::to_string(d.identityCount()));
    }
    if (!expression.empty() && expression.size() != d.expressions.size()) {
        throw Error("FaceModel::vertices: " + std::to_string(expression.size()) + " expression weights given, the model has " +
                    std::to_string(d.expressions.size()));
    }
}

}  // namespace

void FaceModel::vertices(const std::vector<float>& identity, const std::vector<float>& expression, std::vector<Vec3>& out) const {
    const auto& d = *data_;
    checkCoefficients(d, identity, expression);
    const int n = d.vertexCount();
    out.resize(static_cast<std::size_t>(n));
    if (n == 0) return;
    // Straight into `out` (three floats a vertex), in cm until the last step:
    // V = neutral + B_id a, then the sparse expression deltas.
    static_assert(sizeof(Vec3) == 3 * sizeof(float), "Vec3 must be three packed floats");
    Eigen::Map<Eigen::VectorXf> flat(&out.front().x, 3 * static_cast<Eigen::Index>(n));
    flat = Eigen::Map<const Eigen::VectorXf>(d.neutral.data(), 3 * static_cast<Eigen::Index>(n));
    if (!identity.empty()) {
        flat.noalias() += d.identity_basis * Eigen::Map<const Eigen::VectorXf>(identity.data(), static_cast<Eigen::Index>(identity.size()));
    }
    for (std::size_t e = 0; e < expression.size(); ++e) {
        const float w = expression[e];
        if (w == 0.f) continue;
        const auto& shape = d.expressions[e];
        for (std::size_t k = 0; k < shape.vertices.size(); ++k) {
            Vec3& v = out[shape.vertices[k]];
            v.x += w * shape.deltas(0, k);
            v.y += w * shape.deltas(1, k);
            v.z += w * shape.deltas(2, k);
        }
    }
    flat *= 10.f;  // cm -> mm
}

void FaceModel::vertices(const std::vector<float>& identity, const std::vector<float>& expression, const std::vector<int>& which,
                         std::vector<Vec3>& out) const {
    const auto& d = *data_;
    checkCoefficients(d, identity, expression);
    for (const int i : which) {
        if (i < 0 || i >= d.vertexCount()) throw Error("FaceModel::vertices: no vertex " + std::to_string(i));
    }
    out.resize(which.size());
    const Eigen::Map<const Eigen::VectorXf> a(identity.data(), static_cast<Eigen::Index>(identity.size()));
    // The same sum as above, for the rows of `which` only: the expressions' vertex lists are ascending, so each
    // vertex's delta is found by a binary search.
    for (std::size_t k = 0; k < which.size(); ++k) {
        const auto i = static_cast<Eigen::Index>(which[k]);
        Eigen::Vector3f v = d.neutral.col(i);
        if (!identity.empty()) v.noalias() += d.identity_basis.middleRows(3 * i, 3) * a;
        for (std::size_t e = 0; e < expression.size(); ++e) {
            if (expression[e] == 0.f) continue;
            const auto& moving = d.expressions[e].vertices;
            const auto at = std::lower_bound(moving.begin(), moving.end(), static_cast<std::uint32_t>(i));
            if (at == moving.end() || *at != static_cast<std::uint32_t>(i)) continue;
            v += expression[e] * d.expressions[e].deltas.col(at - moving.begin());
        }
        out[k] = {10.f * v.x(), 10.f * v.y(), 10.f * v.z()};  // cm -> mm
    }
}

std::vector<std::array<int, 3>> FaceModel::triangles() const {
    std::vector<std::array<int, 3>> out;
    out.reserve(data_->triangles.size());
    for (const auto& t : data_->triangles) {
        out.push_back({static_cast<int>(t[0]), static_cast<int>(t[1]), static_cast<int>(t[2])});
    }
    return out;
}

int FaceModel::faceVertexCount() const { return static_cast<int>(data_->face_vertex_count); }

namespace {

EyeballGeometry publicEyeball(const model::Eyeball& eye) {
    const auto mm = [](const Eigen::Vector3f& v, float scale) { return Vec3{scale * v.x(), scale * v.y(), scale * v.z()}; };
    return {static_cast<int>(eye.first_vertex),
            static_cast<int>(eye.last_vertex),
            mm(eye.centre, 10.f),
            mm(eye.optical_axis, 1.f),
            10.f * eye.radius,
            10.f * eye.iris_radius};
}

}  // namespace

EyeballGeometry FaceModel::leftEyeball() const { return publicEyeball(data_->left_eye); }
EyeballGeometry FaceModel::rightEyeball() const { return publicEyeball(data_->right_eye); }

}  // namespace facetrack
