// Posing the mesh (public API, facetrack/posed_mesh.hpp): quaternion
// rotations, eyeballs turned by gaze, the mesh in model and camera frames,
// and the head pose as 4x4 matrices.

#include "core/math.hpp"
#include "facetrack/error.hpp"
#include "facetrack/posed_mesh.hpp"
#include "fit/pose.hpp"
#include "test_support.hpp"

#include <cmath>

namespace facetrack {
namespace {

float distance(const Vec3& a, const Vec3& b) { return std::hypot(a.x - b.x, a.y - b.y, a.z - b.z); }

TEST(PosedMesh, RotateAndRotateBackAreInverses) {
    const float h = std::sqrt(0.5f);
    const Quaternion quarterTurnAboutZ{h, 0.f, 0.f, h};
    const Vec3 x{1.f, 0.f, 0.f};
    const Vec3 turned = rotate(quarterTurnAboutZ, x);
    EXPECT_NEAR(turned.x, 0.f, 1e-6f);
    EXPECT_NEAR(turned.y, 1.f, 1e-6f);
    const Vec3 back = rotateBack(quarterTurnAboutZ, turned);
    EXPECT_NEAR(distance(back, x), 0.f, 1e-6f);
}

class EyeRigTest : public ::testing::Test {
protected:
    void SetUp() override { model = FaceModel::load(test::shippedFaceModel()); }
    std::shared_ptr<const FaceModel> model;
};

TEST_F(EyeRigTest, TurnsOnlyTheEyeballAboutItsCentre) {
    const auto eye = model->leftEyeball();
    const EyeRig rig(*model, eye);
    const auto rest = model->vertices({}, {});
    const Vec3 centre = rig.centre(rest);
    EXPECT_LT(distance(centre, eye.centre), 1e-3f);

    auto mesh = rest;
    rig.turn(mesh, eye.optical_axis);  // looking where it already looks: nothing moves
    for (int v = eye.first_vertex; v <= eye.last_vertex; ++v) ASSERT_LT(distance(mesh[v], rest[v]), 1e-4f);

    // 20 degrees towards the subject's left (+x): the iris centre follows, the
    // rest of the face stays, every eyeball vertex keeps its distance to the centre.
    const float a = static_cast<float>(20.0 * core::kRadiansPerDegree);
    const Vec3 axis = eye.optical_axis;
    const Vec3 left{axis.x * std::cos(a) + axis.z * std::sin(a), axis.y, -axis.x * std::sin(a) + axis.z * std::cos(a)};
    rig.turn(mesh, {3.f * left.x, 3.f * left.y, 3.f * left.z});  // need not be unit
    const Vec3 irisRest{centre.x + eye.radius_mm * axis.x, centre.y + eye.radius_mm * axis.y, centre.z + eye.radius_mm * axis.z};
    int nearIris = -1;
    float best = 1e9f;
    for (int v = eye.first_vertex; v <= eye.last_vertex; ++v) {
        ASSERT_NEAR(distance(mesh[v], centre), distance(rest[v], centre), 1e-3f);
        if (distance(rest[v], irisRest) < best) best = distance(rest[v], irisRest), nearIris = v;
    }
    EXPECT_GT(mesh[nearIris].x - rest[nearIris].x, 0.25f * eye.radius_mm * std::sin(a));
    for (int v = 0; v < model->faceVertexCount(); ++v) ASSERT_EQ(distance(mesh[v], rest[v]), 0.f);

    // The centre moves with the identity, so the eye turns in place on any face.
    std::vector<float> identity(model->identityCount(), 0.f);
    identity[0] = 2.f;
    const auto other = model->vertices(identity, {});
    EXPECT_GT(distance(rig.centre(other), centre), 0.f);
}

TEST_F(EyeRigTest, IgnoresDegenerateDirections) {
    const EyeRig rig(*model, model->rightEyeball());
    const auto rest = model->vertices({}, {});
    auto mesh = rest;
    rig.turn(mesh, {0.f, 0.f, 0.f});
    rig.turn(mesh, {NAN, 0.f, 1.f});
    const Vec3 back = model->rightEyeball().optical_axis;
    rig.turn(mesh, {-back.x, -back.y, -back.z});
    for (std::size_t v = 0; v < mesh.size(); ++v) ASSERT_EQ(distance(mesh[v], rest[v]), 0.f);
}

TEST_F(EyeRigTest, VerticesIntoABufferMatchAndReuseIt) {
    std::vector<float> identity(model->identityCount(), 0.f), expression(model->expressionNames().size(), 0.f);
    identity[1] = -1.5f;
    expression[3] = 0.7f;
    const auto fresh = model->vertices(identity, expression);
    std::vector<Vec3> buffer;
    model->vertices(identity, expression, buffer);
    ASSERT_EQ(buffer.size(), fresh.size());
    for (std::size_t v = 0; v < fresh.size(); ++v) ASSERT_EQ(distance(buffer[v], fresh[v]), 0.f);
    const Vec3* memory = buffer.data();
    model->vertices({}, {}, buffer);
    EXPECT_EQ(buffer.data(), memory);  // reused, not reallocated
    EXPECT_THROW(model->vertices({1.f}, {}, buffer), Error);
}

TEST(HeadPoseMatrices, AgreeWithTheQuaternionAndTheDocumentedExample) {
    // The worked example of result.hpp: frontal, 500 mm in front of the camera.
    const HeadPose frontal = fit::headPoseOf(Eigen::Quaterniond(0, 1, 0, 0), Eigen::Vector3d(0, 0, 500));
    const Mat4 camera = {1, 0, 0, 0, 0, -1, 0, 0, 0, 0, -1, 0, 0, 0, 500, 1};
    const Mat4 gl = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -500, 1};
    for (int k = 0; k < 16; ++k) {
        EXPECT_NEAR(frontal.camera_from_model[k], camera[k], 1e-5f) << k;
        EXPECT_NEAR(frontal.gl_model_view[k], gl[k], 1e-5f) << k;
    }
    // Any pose: M x = R x + t, and GL's is the same with y and z negated.
    const HeadPose pose = fit::headPoseOf(
        Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, -0.8, 0.5).normalized())) * Eigen::Quaterniond(0, 1, 0, 0),
        Eigen::Vector3d(-40, 25, 620));
    const Vec3 x{31.f, -12.f, 55.f};
    const Vec3 expected = toCamera(pose, x);
    const Mat4& m = pose.camera_from_model;
    const Vec3 viaMatrix{m[0] * x.x + m[4] * x.y + m[8] * x.z + m[12], m[1] * x.x + m[5] * x.y + m[9] * x.z + m[13],
                         m[2] * x.x + m[6] * x.y + m[10] * x.z + m[14]};
    EXPECT_LT(distance(viaMatrix, expected), 1e-3f);
    for (int col = 0; col < 4; ++col) {
        EXPECT_EQ(m[4 * col + 3], col == 3 ? 1.f : 0.f);
        EXPECT_EQ(pose.gl_model_view[4 * col], m[4 * col]);
        EXPECT_EQ(pose.gl_model_view[4 * col + 1], -m[4 * col + 1]);
        EXPECT_EQ(pose.gl_model_view[4 * col + 2], -m[4 * col + 2]);
    }
}

TEST_F(EyeRigTest, MeshPoserPutsTheFaceWhereTheResultSays) {
    const MeshPoser poser(model);
    FaceResult face;
    std::vector<Vec3> modelMesh, cameraMesh;
    poser.modelFrame(face, modelMesh);  // no identity, no expression: the mean neutral face
    const auto rest = model->vertices({}, {});
    EXPECT_EQ(distance(modelMesh[100], rest[100]), 0.f);
    EXPECT_THROW(poser.cameraFrame(face, cameraMesh), Error);  // no pose

    face.pose = fit::headPoseOf(Eigen::Quaterniond(0, 1, 0, 0), Eigen::Vector3d(10, -20, 500));
    face.expression.emplace();
    face.expression->native.assign(model->expressionNames().size(), 0.f);
    face.expression->native[0] = 1.f;
    poser.modelFrame(face, modelMesh);
    poser.cameraFrame(face, cameraMesh);
    for (std::size_t v = 0; v < modelMesh.size(); v += 997) {
        EXPECT_LT(distance(cameraMesh[v], toCamera(*face.pose, modelMesh[v])), 1e-3f);
    }
    // Gaze straight at the camera turns the eyes; the skin stays.
    face.gaze.emplace();
    face.gaze->left.direction = face.gaze->right.direction = {0.f, 0.3f, -1.f};
    std::vector<Vec3> looking;
    poser.modelFrame(face, looking);
    const auto eye = model->leftEyeball();
    float moved = 0.f;
    for (int v = eye.first_vertex; v <= eye.last_vertex; ++v) moved = std::max(moved, distance(looking[v], modelMesh[v]));
    EXPECT_GT(moved, 1.f);
    for (int v = 0; v < model->faceVertexCount(); v += 101) ASSERT_EQ(distance(looking[v], modelMesh[v]), 0.f);
    const auto centres = poser.eyeCentres(modelMesh);
    EXPECT_GT(centres[0].x, centres[1].x);  // the subject's left eye is at +x
}

}  // namespace
}  // namespace facetrack
