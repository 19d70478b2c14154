// convert_face_model: ICT-FaceKit's FaceXModel folder -> models/face_model.ftm.
//
//   convert_face_model [--source DIR] [--out FILE] [--variance 0.95]
//
// What it derives (docs/models.md has the details):
// - identity: PCA of the 100 source modes restricted to the face region
//   (vertices of the "Face" range), keeping the fewest modes that explain at
//   least --variance of it; the kept modes span all vertices and are scaled
//   so that their coefficients are N(0, 1), like the source's;
// - expressions: all shapes, as sparse deltas (vertices moving > 1e-4 cm);
// - triangles: quads split along their 0-2 diagonal;
// - jaw contour candidates: for each landmark 0..16, face vertices along a
//   path through the landmark that the silhouette follows as the head turns;
// - eyeballs: a least-squares sphere through each sclera, the iris centroid
//   direction as the optical axis, and the radius of the flat iris disc.

#include "app/tool_main.hpp"
#include "core/environment.hpp"
#include "facetrack/error.hpp"
#include "ict_facekit.hpp"
#include "model/face_model_data.hpp"

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <numbers>

namespace facetrack::tools {
namespace {

using Eigen::Vector3f;
using model::FaceModelData;

constexpr float kSparseThreshold = 1e-4f;  // cm; below the source's 6-digit text precision noise

struct Options {
    std::string source;
    std::string out = "models/face_model.ftm";
    double variance = 0.95;
};

nlohmann::json readJson(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw Error("cannot open '" + path + "'");
    return nlohmann::json::parse(in);
}

const nlohmann::json& findRange(const nlohmann::json& regions, const std::string& table, const std::string& name) {
    for (const auto& row : regions.at("ranges").at(table)) {
        if (row.at("name") == name) return row;
    }
    throw Error("regions.json has no range '" + name + "' in '" + table + "'");
}

/// Identity PCA on the face region. delta: modes x (V*3) row-major as stored in the .npy.
void convertIdentity(const NpyArray& identities, std::uint32_t faceVertices, double variance, FaceModelData& out) {
    const auto modes = static_cast<Eigen::Index>(identities.shape.at(0));
    const auto rows = static_cast<Eigen::Index>(identities.shape.at(1) * 3);
    // Columns are modes; row 3v + c is coordinate c of vertex v (our layout).
    const Eigen::Map<const Eigen::MatrixXf> all(identities.values.data(), rows, modes);
    const Eigen::MatrixXd face = all.topRows(3 * faceVertices).cast<double>();
    Eigen::BDCSVD<Eigen::MatrixXd> svd(face, Eigen::ComputeThinV);
    const Eigen::VectorXd energy = svd.singularValues().array().square();
    const double total = energy.sum();
    Eigen::Index keep = 0;
    double explained = 0.0;
    while (keep < energy.size() && explained < variance * total) explained += energy(keep++);
    // With a ~ N(0, I) in the source basis D, c = V_k^T a ~ N(0, I) in the basis D V_k.
    out.identity_basis = (all.cast<double>() * svd.matrixV().leftCols(keep)).cast<float>();
    out.identity_explained_variance = static_cast<float>(explained / total);
    std::printf("identity: kept %ld of %ld modes, %.2f%% of the face region's variance\n", long(keep), long(modes),
                100.0 * explained / total);
}

void convertExpressions(const NpyArray& expressions, const std::vector<std::string>& names, FaceModelData& out) {
    const std::size_t count = expressions.shape.at(0), vertices = expressions.shape.at(1);
    if (names.size() != count) throw Error("expression_names.txt does not match expressions.npy");
    std::size_t stored = 0;
    for (std::size_t j = 0; j < count; ++j) {
        model::SparseBlendshape shape;
        shape.name = names[j];
        const float* d = expressions.values.data() + j * vertices * 3;
        std::vector<float> kept;
        for (std::size_t v = 0; v < vertices; ++v) {
            const Eigen::Map<const Vector3f> delta(d + 3 * v);
            if (delta.cwiseAbs().maxCoeff() > kSparseThreshold) {
                shape.vertices.push_back(static_cast<std::uint32_t>(v));
                kept.insert(kept.end(), delta.data(), delta.data() + 3);
            }
        }
        shape.deltas = Eigen::Map<Eigen::Matrix3Xf>(kept.data(), 3, static_cast<Eigen::Index>(shape.vertices.size()));
        stored += shape.vertices.size();
        out.expressions.push_back(std::move(shape));
    }
    std::printf("expressions: %zu shapes, %zu moving vertices in all (%.1f%% of dense)\n", count, stored,
                100.0 * double(stored) / double(count * vertices));
}

void convertMesh(const ObjMesh& mesh, FaceModelData& out) {
    out.neutral = mesh.vertices;
    out.uvs = mesh.uvs;
    for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
        const auto& ids = mesh.faces[f];
        const auto& uvIds = mesh.face_uvs[f];
        if (uvIds.empty()) throw Error("the neutral mesh has a face without UVs");
        for (std::size_t k = 1; k + 1 < ids.size(); ++k) {  // fan: (0,1,2), (0,2,3)
            out.triangles.push_back({ids[0], ids[k], ids[k + 1]});
            out.triangle_uvs.push_back({uvIds[0], uvIds[k], uvIds[k + 1]});
        }
    }
    std::printf("mesh: %ld vertices, %zu polygons -> %zu triangles, %ld uvs\n", long(mesh.vertices.cols()), mesh.faces.size(),
                out.triangles.size(), long(mesh.uvs.cols()));
}

/// Nearest face-region vertex to p.
std::uint32_t nearestFaceVertex(const FaceModelData& d, const Vector3f& p) {
    Eigen::Index best = 0;
    d.neutral.leftCols(d.face_vertex_count).colwise().operator-(p).colwise().squaredNorm().minCoeff(&best);
    return static_cast<std::uint32_t>(best);
}

/// Jaw contour candidates. Side landmarks (|azimuth| >= 20 deg about the head's
/// vertical axis) slide horizontally around the head: under yaw the silhouette
/// moves from the cheek (frontal) to beside the ear. The path runs in
/// cylindrical coordinates from 10 deg in front of the landmark to 15 deg
/// behind the source's substitute jaw vertex. Chin landmarks slide vertically
/// (pitch): from above the landmark to under the chin.
void convertContour(const nlohmann::json& lists, const nlohmann::json& headRange, FaceModelData& d) {
    const auto substitutesRight = lists.at("Right jawline (substitutes 0-7 in Multi PIE)").get<std::vector<int>>();
    const auto substitutesLeft = lists.at("Left jawline (substitutes 9-16 in Multi PIE)").get<std::vector<int>>();
    // The head's vertical axis: x = 0, at the mean depth of the back-of-head region.
    const Eigen::Index headFirst = headRange.at("vertex_first"), headLast = headRange.at("vertex_last");
    const float axisZ = d.neutral.middleCols(headFirst, headLast - headFirst + 1).row(2).mean();
    auto toCylinder = [&](const Vector3f& p) {
        return Vector3f(std::atan2(p.x(), p.z() - axisZ), p.y(), std::hypot(p.x(), p.z() - axisZ));
    };
    auto fromCylinder = [&](const Vector3f& c) { return Vector3f(c.z() * std::sin(c.x()), c.y(), axisZ + c.z() * std::cos(c.x())); };
    constexpr int kSamples = 16;
    constexpr float kDeg = std::numbers::pi_v<float> / 180.f;
    for (int i = 0; i < model::kContourLandmarkCount; ++i) {
        const Vector3f a = d.neutral.col(d.landmark_vertices[i]);
        int substitute = d.landmark_vertices[i];
        if (i < 8) substitute = substitutesRight.at(i);
        if (i > 8) substitute = substitutesLeft.at(i - 9);
        const Vector3f ca = toCylinder(a), cb = toCylinder(d.neutral.col(substitute));
        auto& list = d.contour_candidates[i];
        list.clear();
        for (int s = 0; s < kSamples; ++s) {
            const float t = float(s) / float(kSamples - 1);
            Vector3f p;
            if (std::abs(ca.x()) >= 20.f * kDeg) {
                const float side = ca.x() > 0 ? 1.f : -1.f;
                const float front = ca.x() - side * 10.f * kDeg;
                const float back = std::clamp(cb.x() + side * 15.f * kDeg, -80.f * kDeg, 80.f * kDeg);
                const float u = (front + t * (back - front) - ca.x()) / (cb.x() - ca.x() + side * 1e-3f);
                const Vector3f c(front + t * (back - front), ca.y() + u * (cb.y() - ca.y()), ca.z() + u * (cb.z() - ca.z()));
                p = fromCylinder(c);
            } else {
                p = a + Vector3f(0.f, 1.0f, 0.3f) + t * Vector3f(0.f, -2.5f, -2.3f);
            }
            const auto v = nearestFaceVertex(d, p);
            if (std::find(list.begin(), list.end(), v) == list.end()) list.push_back(v);
        }
        // The landmark's own vertex is always a candidate, first.
        list.erase(std::remove(list.begin(), list.end(), d.landmark_vertices[i]), list.end());
        list.insert(list.begin(), d.landmark_vertices[i]);
    }
}

model::Eyeball convertEyeball(const FaceModelData& d, const nlohmann::json& eyeball, const nlohmann::json& iris) {
    model::Eyeball e;
    e.first_vertex = eyeball.at("vertex_first");
    e.last_vertex = eyeball.at("vertex_last");
    const std::uint32_t irisFirst = iris.at("vertex_first"), irisLast = iris.at("vertex_last");
    // Sphere through the sclera (vertices before the iris): |p|^2 = 2 c.p + k, linear in (c, k).
    const Eigen::Index n = irisFirst - e.first_vertex;
    Eigen::MatrixXd A(n, 4);
    Eigen::VectorXd b(n);
    for (Eigen::Index i = 0; i < n; ++i) {
        const Eigen::Vector3d p = d.neutral.col(e.first_vertex + i).cast<double>();
        A.row(i) << 2 * p.x(), 2 * p.y(), 2 * p.z(), 1.0;
        b(i) = p.squaredNorm();
    }
    const Eigen::Vector4d x = A.colPivHouseholderQr().solve(b);
    e.centre = x.head<3>().cast<float>();
    e.radius = static_cast<float>(std::sqrt(x(3) + x.head<3>().squaredNorm()));
    const auto irisPoints = d.neutral.middleCols(irisFirst, irisLast - irisFirst + 1);
    e.optical_axis = (irisPoints.rowwise().mean() - e.centre).normalized();
    // The iris mesh also lines the inside of the eyeball; its visible disc is
    // the flat front part, within 1.2 mm of its most anterior vertex. The rim
    // is that disc's largest distance from the optical axis.
    float front = -1e9f;
    for (Eigen::Index i = 0; i < irisPoints.cols(); ++i) {
        front = std::max(front, (irisPoints.col(i) - e.centre).dot(e.optical_axis));
    }
    float rim = 0.f;
    for (Eigen::Index i = 0; i < irisPoints.cols(); ++i) {
        const Vector3f r = irisPoints.col(i) - e.centre;
        const float axial = r.dot(e.optical_axis);
        if (axial >= front - 0.12f) rim = std::max(rim, (r - axial * e.optical_axis).norm());
    }
    e.iris_radius = rim;
    std::printf("eyeball %u-%u: centre (%.3f, %.3f, %.3f), radius %.3f, iris radius %.3f\n", e.first_vertex, e.last_vertex, e.centre.x(),
                e.centre.y(), e.centre.z(), e.radius, e.iris_radius);
    return e;
}

FaceModelData convert(const Options& o) {
    const std::string dir = o.source + "/";
    const auto regions = readJson(dir + "regions.json");
    FaceModelData d;
    convertMesh(readObj(dir + "generic_neutral_mesh.obj"), d);
    const auto& face = findRange(regions, "Face Model Topology", "Face");
    d.face_vertex_count = face.at("vertex_last").get<std::uint32_t>() + 1;

    const auto identities = readNpy(dir + "identities.npy");
    const auto expressions = readNpy(dir + "expressions.npy");
    for (const auto* a : {&identities, &expressions}) {
        if (a->shape.size() != 3 || a->shape[1] != std::size_t(d.neutral.cols()) || a->shape[2] != 3) {
            throw Error("a .npy array does not match the neutral mesh's vertex count");
        }
    }
    convertIdentity(identities, d.face_vertex_count, o.variance, d);
    convertExpressions(expressions, readLines(dir + "expression_names.txt"), d);

    const auto landmarks = readLines(dir + "landmarks_multipie68.txt");
    if (landmarks.size() != model::kLandmarkCount) throw Error("landmarks_multipie68.txt must have 68 lines");
    for (int i = 0; i < model::kLandmarkCount; ++i) d.landmark_vertices[i] = std::stoul(landmarks[i]);
    convertContour(regions.at("landmark_lists"), findRange(regions, "Face Model Topology", "Head and Neck"), d);

    d.left_eye = convertEyeball(d, findRange(regions, "Face Model Topology", "Eyeball left"),
                                findRange(regions, "Eyeball Details", "Iris left"));
    d.right_eye = convertEyeball(d, findRange(regions, "Face Model Topology", "Eyeball right"),
                                 findRange(regions, "Eyeball Details", "Iris right"));
    return d;
}

int run(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) throw Error(arg + " needs a value");
            return argv[++i];
        };
        if (arg == "--source") o.source = value();
        else if (arg == "--out") o.out = value();
        else if (arg == "--variance") o.variance = std::stod(value());
        else if (arg == "-h" || arg == "--help") {
            std::puts("usage: convert_face_model [--source FaceXModel-dir] [--out models/face_model.ftm] [--variance 0.95]");
            return 0;
        } else throw Error("unknown option '" + arg + "' (see --help)");
    }
    if (o.source.empty()) {
        const std::string shared = core::sharedDirectory();
        if (shared.empty()) throw Error("no --source given and ../shared not found");
        o.source = shared + "/models/ict-facekit/FaceXModel";
    }
    if (!(o.variance > 0.0 && o.variance <= 1.0)) throw Error("--variance must be in (0, 1]");
    const FaceModelData d = convert(o);
    model::writeFaceModel(o.out, d);
    std::ifstream written(o.out, std::ios::binary | std::ios::ate);
    std::printf("wrote %s (%.1f MB)\n", o.out.c_str(), double(written.tellg()) / 1e6);
    return 0;
}

}  // namespace
}  // namespace facetrack::tools

int main(int argc, char** argv) { return facetrack::tools::runTool("convert_face_model", facetrack::tools::run, argc, argv); }
