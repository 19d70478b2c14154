// The dense teacher labels' pieces (tools/data/dense): nearest points on triangles,
// the teacher's file formats, the correspondence to the face model, and the
// dense fit on synthetic faces of known parameters.

#include "data/dense/correspondence.hpp"
#include "data/dense/dense_fit.hpp"
#include "data/dense/mediapipe_mesh.hpp"
#include "facetrack/error.hpp"
#include "facetrack/face_model.hpp"
#include "model/internals.hpp"
#include "test_support.hpp"

#include <fstream>
#include <random>

namespace facetrack {
namespace {

TEST(ClosestOnTriangle, MatchesDenseSamplingOfTheTriangle) {
    std::mt19937 rng(3);
    std::normal_distribution<double> g(0.0, 1.0);
    for (int trial = 0; trial < 200; ++trial) {
        const Eigen::Vector3d a(g(rng), g(rng), g(rng)), b(g(rng), g(rng), g(rng)), c(g(rng), g(rng), g(rng));
        const Eigen::Vector3d p(2 * g(rng), 2 * g(rng), 2 * g(rng));
        const Eigen::Vector3d w = dense::closestOnTriangle(p, a, b, c);
        EXPECT_NEAR(w.sum(), 1.0, 1e-12);
        EXPECT_GE(w.minCoeff(), -1e-12);
        const double d = (p - (w[0] * a + w[1] * b + w[2] * c)).norm();
        double best = 1e9;
        for (int i = 0; i <= 100; ++i)
            for (int j = 0; i + j <= 100; ++j) {
                const double u = i / 100.0, v = j / 100.0;
                best = std::min(best, (p - ((1 - u - v) * a + u * b + v * c)).norm());
            }
        EXPECT_LE(d, best + 1e-9);
        EXPECT_GE(d, best - 0.05);  // the sampling's own resolution
    }
}

TEST(TeacherMeshes, ReadsRowsAndRejectsAShapeThatDoesNotMatch) {
    const std::string jsonl = test::tempPath("mesh.jsonl"), npy = test::tempPath("mesh.npy");
    std::ofstream(jsonl) << R"({"image": "afw/a.jpg", "width": 256, "height": 200, "found": true})" << '\n'
                         << R"({"clip": "c.mp4", "frame": 7, "width": 64, "height": 48, "found": false})" << '\n';
    auto writeNpy = [&](int rows) {
        std::string header = "{'descr': '<i2', 'fortran_order': False, 'shape': (" + std::to_string(rows) + ", 478, 3), }";
        header.resize(117, ' ');
        header += '\n';
        std::ofstream out(npy, std::ios::binary);
        out.write("\x93NUMPY\x01\x00", 8);
        const char length[2] = {static_cast<char>(header.size()), 0};
        out.write(length, 2);
        out << header;
        std::vector<std::int16_t> v(static_cast<std::size_t>(rows) * 478 * 3, 0);
        v[3 * 5] = 16 * 10 + 8;  // row 0, vertex 5: x = 10.5
        v[3 * 5 + 1] = -16 * 2;  // y = -2
        out.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(v.size() * 2));
    };
    writeNpy(2);
    const auto m = dense::readTeacherMeshes(jsonl, npy);
    ASSERT_EQ(m.rows(), 2);
    EXPECT_EQ(m.keys[0], "afw/a.jpg");
    EXPECT_EQ(m.keys[1], "c.mp4#7");
    EXPECT_TRUE(m.found[0]);
    EXPECT_FALSE(m.found[1]);
    EXPECT_EQ(m.width[0], 256);
    EXPECT_EQ(m.height[1], 48);
    EXPECT_DOUBLE_EQ(m.points(0)(0, 5), 10.5);
    EXPECT_DOUBLE_EQ(m.points(0)(1, 5), -2.0);
    writeNpy(3);
    EXPECT_THROW(dense::readTeacherMeshes(jsonl, npy), Error);
    EXPECT_THROW(dense::readTeacherMeshes(jsonl, npy + ".missing"), Error);
    std::remove(jsonl.c_str());
    std::remove(npy.c_str());
}

/// Surface points spread over the model's face region: every 40th face triangle's centre.
std::vector<fit::SurfacePoint> spreadPoints(const model::FaceModelData& data) {
    std::vector<fit::SurfacePoint> points;
    for (std::size_t t = 0; t < data.triangles.size(); t += 40) {
        const auto& tri = data.triangles[t];
        if (tri[0] >= data.face_vertex_count || tri[1] >= data.face_vertex_count || tri[2] >= data.face_vertex_count) continue;
        fit::SurfacePoint p;
        p.vertices = tri;
        p.weights = Eigen::Vector3d::Constant(1.0 / 3.0);
        points.push_back(p);
    }
    return points;
}

TEST(DenseFit, RecoversPoseAndObservableExpressionsOfSyntheticFaces) {
    const auto model = FaceModel::load(test::shippedFaceModel());
    const auto& data = model::dataOf(*model);
    const auto points = spreadPoints(data);
    ASSERT_GT(points.size(), 150u);
    const auto observable = fit::observableExpressions(data, points);
    dense::DenseModel m;
    m.basis = fit::buildPointBasis(data, points, observable);
    m.observable.assign(observable.size(), true);
    // The eye corners: the points nearest the landmark vertices 36 and 45.
    for (int side = 0; side < 2; ++side) {
        const Eigen::Vector3d corner = fit::modelToFrontal() * data.neutral.col(data.landmark_vertices[side == 0 ? 36 : 45]).cast<double>();
        (m.basis.neutral.colwise() - corner).colwise().squaredNorm().minCoeff(&m.eye_corner_slots[static_cast<std::size_t>(side)]);
    }
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> unit(0.0, 1.0), sym(-1.0, 1.0);
    std::normal_distribution<double> noise(0.0, 0.5);
    const dense::DenseFitSettings settings;
    double rotationError = 0.0, expressionSquares = 0.0;
    int expressionCount = 0;
    constexpr int kFaces = 10;
    for (int face = 0; face < kFaces; ++face) {
        Eigen::VectorXd identity(m.basis.identityCount());
        for (auto& a : identity) a = 0.7 * sym(rng);
        fit::FaceParams truth;
        truth.pose.head<3>() = fit::omegaFromEuler({15.0 * sym(rng), 35.0 * sym(rng), 10.0 * sym(rng)});
        truth.pose.tail<3>() = Eigen::Vector3d(4.0 * sym(rng), 3.0 * sym(rng), 45.0 + 20.0 * unit(rng));
        truth.expression = Eigen::VectorXd::Zero(m.basis.expressionCount());
        for (auto& b : truth.expression) b = unit(rng) < 0.3 ? unit(rng) : 0.0;
        dense::DenseFrame frame;
        frame.camera = core::cameraFor(640, 480, 60.0, 0.0);
        frame.observed = dense::projectPoints(m, identity, frame.camera, truth);
        for (auto& v : frame.observed.reshaped()) v += noise(rng);
        dense::fitFrame(m, settings, identity, frame, false);
        const Eigen::Matrix3d dR = fit::rotationOf(frame.params.omega()) * fit::rotationOf(truth.omega()).transpose();
        rotationError += std::acos(std::clamp((dR.trace() - 1.0) / 2.0, -1.0, 1.0)) * 180.0 / M_PI / kFaces;
        expressionSquares += (frame.params.expression - truth.expression).squaredNorm();
        expressionCount += static_cast<int>(truth.expression.size());
        EXPECT_LT(frame.residual, 0.02);
    }
    const double rms = std::sqrt(expressionSquares / expressionCount);
    EXPECT_LT(rotationError, 1.0) << "mean rotation error, degrees";
    EXPECT_LT(rms, 0.05) << "RMS expression error over the observable shapes";
}

TEST(DenseCorrespondence, CanonicalMeshLiesOnTheModelAndFitsNoExpression) {
    FACETRACK_REQUIRE_SHARED();
    const auto model = FaceModel::load(test::shippedFaceModel());
    const auto& data = model::dataOf(*model);
    const auto canonical = dense::readCanonicalMesh(test::sharedDir() + "/models/mediapipe-canonical/canonical_face_model.obj");
    const auto corr = dense::buildCorrespondence(data, canonical.vertices);
    EXPECT_GE(corr.usableCount(), 440);
    std::vector<double> d = corr.distance_cm;
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
    EXPECT_LT(d[d.size() / 2], 0.1) << "median distance to the surface, cm";
    EXPECT_NEAR(corr.scale, 1.0, 0.05) << "both meshes are in centimetres";
    // MediaPipe's upper and lower inner lip midpoints (13, 14) land on the model's upper and lower lip:
    // only the lower one moves with jawOpen.
    const auto jawOpen = std::find_if(data.expressions.begin(), data.expressions.end(), [](const auto& e) { return e.name == "jawOpen"; });
    ASSERT_NE(jawOpen, data.expressions.end());
    auto drop = [&](int mediapipe) {
        double dy = 0.0;
        const auto& p = corr.points[static_cast<std::size_t>(mediapipe)];
        for (int c = 0; c < 3; ++c) {
            const auto it = std::lower_bound(jawOpen->vertices.begin(), jawOpen->vertices.end(), p.vertices[c]);
            if (it != jawOpen->vertices.end() && *it == p.vertices[c])
                dy += p.weights[c] * jawOpen->deltas(1, it - jawOpen->vertices.begin());
        }
        return -dy;
    };
    EXPECT_LT(drop(13), 0.5);
    EXPECT_GT(drop(14), 2.0);

    const std::vector<int> vertices = corr.usableVertices();
    const dense::DenseModel m = dense::denseModel(data, corr, dense::labelledExpressions(data));
    for (const double yaw : {0.0, 30.0}) {
        std::vector<dense::DenseFrame> one{dense::canonicalFrame(corr, canonical.vertices, vertices, yaw)};
        dense::fitIdentity(m, dense::DenseFitSettings(), one);
        EXPECT_LT(one[0].params.expression.maxCoeff(), 0.10) << "yaw " << yaw;
        EXPECT_LT(one[0].residual, 0.015) << "yaw " << yaw;
    }
}

TEST(DenseObservability, MediaPipePointsObserveBrowsSquintAndLipShapesThatLandmarksCannot) {
    FACETRACK_REQUIRE_SHARED();
    const auto model = FaceModel::load(test::shippedFaceModel());
    const auto& data = model::dataOf(*model);
    const auto canonical = dense::readCanonicalMesh(test::sharedDir() + "/models/mediapipe-canonical/canonical_face_model.obj");
    const auto corr = dense::buildCorrespondence(data, canonical.vertices);
    std::vector<fit::SurfacePoint> points;
    for (const int v : corr.usableVertices()) points.push_back(corr.points[static_cast<std::size_t>(v)]);
    const auto dense = fit::observableExpressions(data, points);
    auto has = [&](const std::vector<int>& list, const std::string& name) {
        return std::any_of(list.begin(), list.end(), [&](int e) { return data.expressions[static_cast<std::size_t>(e)].name == name; });
    };
    const auto& landmarks = fit::basisOf(model)->expressions;
    for (const char* name : {"browDown_L", "browInnerUp_R", "eyeSquint_L", "mouthStretch_R", "mouthDimple_L"}) {
        EXPECT_TRUE(has(dense, name)) << name;
        EXPECT_FALSE(has(landmarks, name)) << name;
    }
    for (const int e : landmarks) EXPECT_TRUE(has(dense, data.expressions[static_cast<std::size_t>(e)].name));
    for (const int e : dense) EXPECT_NE(data.expressions[static_cast<std::size_t>(e)].name.rfind("eyeLook", 0), 0u);
}

}  // namespace
}  // namespace facetrack
