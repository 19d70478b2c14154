#include "core/pts.hpp"
#include "core/shape2d.hpp"
#include "facetrack/error.hpp"
#include "facetrack/face_model.hpp"
#include "fit/fit_basis.hpp"
#include "model/face_model_data.hpp"
#include "model/internals.hpp"
#include "model/landmark_convention.hpp"
#include "test_support.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

namespace facetrack {
namespace {

namespace fs = std::filesystem;

model::FaceModelData tinyModel() {
    model::FaceModelData d;
    d.neutral = Eigen::Matrix3Xf::Random(3, 6);
    d.identity_basis = Eigen::MatrixXf::Random(18, 2);
    d.identity_explained_variance = 0.97f;
    d.face_vertex_count = 4;
    model::SparseBlendshape jaw{"jawOpen", {1, 4}, Eigen::Matrix3Xf::Random(3, 2)};
    d.expressions = {jaw};
    d.triangles = {{0, 1, 2}, {2, 3, 4}};
    d.uvs = Eigen::Matrix2Xf::Random(2, 7);
    d.triangle_uvs = {{0, 1, 2}, {5, 6, 4}};
    for (int i = 0; i < model::kLandmarkCount; ++i) d.landmark_vertices[i] = i % 6;
    for (auto& list : d.contour_candidates) list = {0, 3};
    d.left_eye = {4, 5, {1.f, 2.f, 3.f}, {0.f, 0.f, 1.f}, 1.5f, 0.6f};
    d.right_eye = {4, 5, {-1.f, 2.f, 3.f}, {0.f, 0.f, 1.f}, 1.5f, 0.6f};
    return d;
}

std::string copyOfShippedModel(const std::string& name) {
    const std::string path = test::tempPath(name);
    fs::copy_file(test::shippedFaceModel(), path, fs::copy_options::overwrite_existing);
    return path;
}

std::string loadError(const std::string& path) {
    try {
        FaceModel::load(path);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

TEST(FaceModelFile, WriteReadRoundTrip) {
    const model::FaceModelData d = tinyModel();
    const std::string path = test::tempPath("tiny.ftm");
    model::writeFaceModel(path, d);
    const model::FaceModelData back = model::readFaceModel(path);
    fs::remove(path);

    EXPECT_EQ(back.neutral, d.neutral);
    // The identity basis is stored in half precision.
    EXPECT_LT((back.identity_basis - d.identity_basis).cwiseAbs().maxCoeff(), 1e-3f);
    EXPECT_EQ(back.identity_explained_variance, d.identity_explained_variance);
    EXPECT_EQ(back.face_vertex_count, d.face_vertex_count);
    ASSERT_EQ(back.expressions.size(), 1u);
    EXPECT_EQ(back.expressions[0].name, "jawOpen");
    EXPECT_EQ(back.expressions[0].vertices, d.expressions[0].vertices);
    EXPECT_EQ(back.expressions[0].deltas, d.expressions[0].deltas);
    EXPECT_EQ(back.triangles, d.triangles);
    EXPECT_EQ(back.uvs, d.uvs);
    EXPECT_EQ(back.triangle_uvs, d.triangle_uvs);
    EXPECT_EQ(back.landmark_vertices, d.landmark_vertices);
    EXPECT_EQ(back.contour_candidates, d.contour_candidates);
    EXPECT_EQ(back.left_eye.centre, d.left_eye.centre);
    EXPECT_EQ(back.right_eye.iris_radius, d.right_eye.iris_radius);
}

TEST(FaceModelFile, InconsistentDataIsNotWritten) {
    model::FaceModelData d = tinyModel();
    d.triangles.push_back({0, 1, 99});
    EXPECT_THROW(model::writeFaceModel(test::tempPath("bad.ftm"), d), Error);
}

TEST(ShippedFaceModel, HasWhatTheTrackerNeeds) {
    const auto m = FaceModel::load(test::shippedFaceModel());
    const auto& d = model::dataOf(*m);
    EXPECT_EQ(m->vertexCount(), 26719);
    EXPECT_EQ(m->triangleCount(), 2 * 25836 + 548);  // quads split, triangles kept
    EXPECT_GE(m->identityExplainedVariance(), 0.95f);
    EXPECT_GE(m->identityCount(), 5);
    EXPECT_EQ(m->expressionNames().size(), 57u);
    EXPECT_EQ(m->expressionNames()[26], "jawOpen");
    EXPECT_EQ(d.face_vertex_count, 9409u);

    // Identity modes are scaled to unit-variance coefficients: the first ones move vertices by millimetres.
    EXPECT_GT(d.identity_basis.col(0).cwiseAbs().maxCoeff(), 0.1f);

    for (int i = 0; i < model::kContourLandmarkCount; ++i) {
        const auto& list = d.contour_candidates[i];
        EXPECT_EQ(list.front(), d.landmark_vertices[i]) << "contour " << i;
        EXPECT_GE(list.size(), 4u) << "contour " << i;
        for (auto v : list) EXPECT_LT(v, d.face_vertex_count) << "contour " << i;
    }
    // Side contour candidates move back around the head, towards the ear.
    const Eigen::Vector3f first = d.neutral.col(d.contour_candidates[2].front());
    const Eigen::Vector3f last = d.neutral.col(d.contour_candidates[2].back());
    EXPECT_LT(last.z(), first.z() - 0.5f);

    EXPECT_GT(d.left_eye.centre.x(), 2.5f);  // subject's left is +x
    EXPECT_LT(d.right_eye.centre.x(), -2.5f);
    for (const auto* eye : {&d.left_eye, &d.right_eye}) {
        EXPECT_NEAR(eye->radius, 1.58f, 0.05f);
        EXPECT_GT(eye->iris_radius, 0.5f);  // human iris: about 0.6 cm
        EXPECT_LT(eye->iris_radius, 0.7f);
        EXPECT_GT(eye->optical_axis.z(), 0.95f);
    }
}

// The vertices of a subset are the whole mesh's, for any identity and expression; an index outside the mesh throws.
TEST(ShippedFaceModel, TheVerticesOfASubsetAreTheWholeMeshs) {
    const auto m = FaceModel::load(test::shippedFaceModel());
    std::mt19937 rng(3);
    std::normal_distribution<float> normal(0.f, 1.f);
    std::uniform_real_distribution<float> unit(0.f, 1.f);
    std::vector<float> identity(static_cast<std::size_t>(m->identityCount())), expression(m->expressionNames().size());
    for (float& a : identity) a = normal(rng);
    for (float& b : expression) b = unit(rng) < 0.3f ? unit(rng) : 0.f;
    expression[26] = 0.8f;  // jawOpen: the chin's and lips' vertices move
    std::vector<int> which = m->landmarkVertices();
    which.push_back(0);
    which.push_back(m->vertexCount() - 1);
    for (const auto& [id, ex] : {std::pair{identity, expression}, std::pair{std::vector<float>{}, std::vector<float>{}}}) {
        const std::vector<Vec3> mesh = m->vertices(id, ex);
        std::vector<Vec3> subset;
        m->vertices(id, ex, which, subset);
        ASSERT_EQ(subset.size(), which.size());
        for (std::size_t k = 0; k < which.size(); ++k) {
            const Vec3& v = mesh[static_cast<std::size_t>(which[k])];
            EXPECT_NEAR(subset[k].x, v.x, 1e-3f) << which[k];
            EXPECT_NEAR(subset[k].y, v.y, 1e-3f) << which[k];
            EXPECT_NEAR(subset[k].z, v.z, 1e-3f) << which[k];
        }
    }
    EXPECT_GT(std::abs(m->vertices({}, expression)[static_cast<std::size_t>(m->landmarkVertices()[8])].y -
                       m->vertices({}, {})[static_cast<std::size_t>(m->landmarkVertices()[8])].y),
              1.f);  // the chin moved
    std::vector<Vec3> out;
    EXPECT_THROW(m->vertices({}, {}, {m->vertexCount()}, out), Error);
    EXPECT_THROW(m->vertices({}, {}, {-1}, out), Error);
    EXPECT_THROW(m->vertices({1.f}, {}, {0}, out), Error);
}

TEST(ShippedFaceModel, CorruptCopyGivesAClearError) {
    const std::string path = copyOfShippedModel("corrupt.ftm");
    {
        std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(1000);
        f.put('\x7f');
    }
    const std::string msg = loadError(path);
    fs::remove(path);
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("corrupt"), std::string::npos) << msg;
}

TEST(ShippedFaceModel, TruncatedCopyGivesAClearError) {
    const std::string path = copyOfShippedModel("truncated.ftm");
    fs::resize_file(path, fs::file_size(path) / 2);
    const std::string msg = loadError(path);
    fs::remove(path);
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;
}

TEST(ShippedFaceModel, OtherVersionGivesAClearError) {
    const std::string path = copyOfShippedModel("version.ftm");
    {
        std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(8);  // the version field
        const std::uint32_t future = model::kFaceModelVersion + 1;
        f.write(reinterpret_cast<const char*>(&future), 4);
    }
    const std::string msg = loadError(path);
    fs::remove(path);
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("format version " + std::to_string(model::kFaceModelVersion + 1)), std::string::npos) << msg;
}

TEST(ShippedFaceModel, MissingFileGivesAClearError) {
    const std::string msg = loadError("/nonexistent/face_model.ftm");
    EXPECT_NE(msg.find("/nonexistent/face_model.ftm"), std::string::npos) << msg;
}

// The model's 68 landmark vertices, seen frontally, against the mean 300-W shape.
TEST(ShippedFaceModel, FrontalLandmarksMatchThe300WMeanShape) {
    FACETRACK_REQUIRE_SHARED();
    std::vector<core::Shape2> shapes;
    for (const char* subset : {"helen/trainset", "lfpw/trainset", "afw"}) {
        for (const auto& entry : fs::directory_iterator(test::sharedDir() + "/data/faces300w/" + subset)) {
            if (entry.path().extension() == ".pts") shapes.push_back(core::readPts(entry.path().string()));
        }
    }
    ASSERT_GT(shapes.size(), 1000u);
    const core::Shape2 mean = core::procrustesMean(shapes);

    const auto m = FaceModel::load(test::shippedFaceModel());
    core::Shape2 projected(2, 68);
    for (int i = 0; i < 68; ++i) {
        const Eigen::Vector3f v = model::dataOf(*m).neutral.col(model::dataOf(*m).landmark_vertices[i]);
        projected.col(i) = Eigen::Vector2f(v.x(), -v.y());  // orthographic, image y down
    }
    const core::Shape2 aligned = core::alignSimilarity(projected, mean).apply(projected);
    const float nme = core::nme68(aligned, mean);
    RecordProperty("nme_percent", std::to_string(100.f * nme));
    std::printf("frontal model landmarks vs 300-W mean shape: NME %.2f%%\n", 100.f * nme);
    EXPECT_LT(nme, 0.10f);
    // The mirror image must fit worse: the model's left/right agree with iBUG's.
    core::Shape2 mirrored = projected;
    mirrored.row(0) *= -1.f;
    EXPECT_GT(core::nme68(core::alignSimilarity(mirrored, mean).apply(mirrored), mean), nme);
}

// The shipped file is exactly what the converter makes from ../shared.
TEST(ShippedFaceModel, ConverterReproducesTheShippedFile) {
    FACETRACK_REQUIRE_SHARED();
    const std::string out = test::tempPath("converted.ftm");
    const std::string cmd = std::string(FACETRACK_CONVERTER) + " --source '" + test::sharedDir() +
                            "/models/ict-facekit/FaceXModel' --out '" + out + "' > /dev/null";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    std::ifstream a(out, std::ios::binary), b(test::shippedFaceModel(), std::ios::binary);
    const std::string bytesA((std::istreambuf_iterator<char>(a)), {}), bytesB((std::istreambuf_iterator<char>(b)), {});
    fs::remove(out);
    EXPECT_TRUE(bytesA == bytesB) << "models/face_model.ftm is stale: regenerate it (models/README.md)";
}

}  // namespace
}  // namespace facetrack

namespace facetrack {
namespace {

TEST(LandmarkConvention, RoundTripsMovesOnlyTheLandmarkSlotsAndRejectsDamage) {
    const std::string shipped = test::sourceDir() + "/models/landmark_convention.ftm";
    if (!std::filesystem::exists(shipped))
        GTEST_SKIP() << "models/landmark_convention.ftm is missing (build/tools/train_convention makes it)";
    const model::LandmarkConvention c = model::readLandmarkConvention(shipped);
    // Jaw landmarks keep their vertices; the others move by millimetres, not centimetres.
    EXPECT_EQ(c.offsets_frontal_cm.leftCols(model::kContourLandmarkCount).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_GT(c.offsets_frontal_cm.cwiseAbs().maxCoeff(), 0.05);
    EXPECT_LT(c.offsets_frontal_cm.cwiseAbs().maxCoeff(), 1.5);
    // Symmetric: landmark 36's offset is landmark 45's with x negated.
    EXPECT_NEAR(c.offsets_frontal_cm(0, 36), -c.offsets_frontal_cm(0, 45), 1e-9);
    EXPECT_NEAR(c.offsets_frontal_cm(1, 36), c.offsets_frontal_cm(1, 45), 1e-9);

    const auto bare = FaceModel::load(test::shippedFaceModel());
    const auto with = FaceModel::load(test::shippedFaceModel(), shipped);
    EXPECT_EQ(with->conventionPath(), shipped);
    EXPECT_TRUE(bare->conventionPath().empty());
    const fit::FitBasis& a = *fit::basisOf(bare);
    const fit::FitBasis& b = *fit::basisOf(with);
    ASSERT_EQ(a.slotCount(), b.slotCount());
    int moved = 0;
    for (int s = 0; s < a.slotCount(); ++s) moved += (a.neutral.col(s) - b.neutral.col(s)).norm() > 0.0 ? 1 : 0;
    EXPECT_EQ(moved, model::kLandmarkCount - model::kContourLandmarkCount);
    EXPECT_TRUE(a.identity.isApprox(b.identity));
    // The mesh itself is the model's: the convention is the fit's business.
    EXPECT_EQ(bare->vertices({}, {})[100].x, with->vertices({}, {})[100].x);

    // The expression prior: a factor per listed shape, 1 for the others.
    const auto names = b.expressionNames(model::dataOf(*with));
    for (std::size_t k = 0; k < names.size(); ++k) {
        const auto it = c.expression_prior.find(names[k]);
        EXPECT_EQ(b.expression_prior[static_cast<Eigen::Index>(k)], it == c.expression_prior.end() ? 1.0 : it->second) << names[k];
        EXPECT_EQ(a.expression_prior[static_cast<Eigen::Index>(k)], 1.0);
    }

    const std::string copy = test::tempPath("convention.ftm");
    model::LandmarkConvention withPrior = c;
    withPrior.expression_prior["jawOpen"] = 0.25;
    model::writeLandmarkConvention(copy, withPrior);
    EXPECT_EQ(model::readLandmarkConvention(copy).offsets_frontal_cm, c.offsets_frontal_cm);
    EXPECT_EQ(model::readLandmarkConvention(copy).expression_prior, withPrior.expression_prior);
    {
        std::fstream f(copy, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(60);
        f.put('\x55');
    }
    EXPECT_THROW(FaceModel::load(test::shippedFaceModel(), copy), Error);
    EXPECT_THROW(FaceModel::load(test::shippedFaceModel(), test::tempPath("no_convention.ftm")), Error);
    model::LandmarkConvention wild = c;
    wild.offsets_frontal_cm(0, 30) = 5.0;
    EXPECT_THROW(model::writeLandmarkConvention(copy, wild), Error);
    model::LandmarkConvention negative = c;
    negative.expression_prior["jawOpen"] = -1.0;
    EXPECT_THROW(model::writeLandmarkConvention(copy, negative), Error);
    std::filesystem::remove(copy);
}

/// landmarkPoints is the fit basis's landmark slots in the model frame: the
/// same points whether read off a mesh or off the basis the fit uses.
TEST(LandmarkConvention, LandmarkPointsAreTheFitsLandmarksOnTheMesh) {
    const std::string shipped = test::sourceDir() + "/models/landmark_convention.ftm";
    if (!std::filesystem::exists(shipped))
        GTEST_SKIP() << "models/landmark_convention.ftm is missing (build/tools/train_convention makes it)";
    const auto bare = FaceModel::load(test::shippedFaceModel());
    const auto with = FaceModel::load(test::shippedFaceModel(), shipped);
    const std::vector<Vec3> mesh = with->vertices({}, {});
    const std::vector<int> vertices = with->landmarkVertices();
    const std::vector<Vec3> plain = bare->landmarkPoints(mesh), moved = with->landmarkPoints(mesh);
    ASSERT_EQ(moved.size(), 68u);
    const fit::FitBasis& basis = *fit::basisOf(with);
    double largest = 0.0;
    for (std::size_t i = 0; i < 68; ++i) {
        const Vec3& v = mesh[static_cast<std::size_t>(vertices[i])];
        EXPECT_EQ(plain[i].x, v.x);
        EXPECT_EQ(plain[i].z, v.z);
        // The basis is in cm, turned by R_0 = diag(1, -1, -1).
        const Eigen::Vector3d slot = basis.neutral.col(basis.landmark_slots[i]);
        EXPECT_NEAR(moved[i].x, 10.0 * slot.x(), 1e-3) << i;
        EXPECT_NEAR(moved[i].y, -10.0 * slot.y(), 1e-3) << i;
        EXPECT_NEAR(moved[i].z, -10.0 * slot.z(), 1e-3) << i;
        largest = std::max(largest, static_cast<double>(std::hypot(moved[i].x - v.x, moved[i].y - v.y, moved[i].z - v.z)));
    }
    EXPECT_GT(largest, 1.0);  // millimetres: the convention moves some landmarks
    EXPECT_THROW(with->landmarkPoints(std::vector<Vec3>(10)), Error);
}

}  // namespace
}  // namespace facetrack
