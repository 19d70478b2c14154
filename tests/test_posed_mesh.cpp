// The mesh helpers the overlay and the avatar share: quaternion rotations and
// eyeballs turned by gaze.

#include "facetrack/posed_mesh.hpp"
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
    const float a = 20.f * 3.14159265f / 180.f;
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

}  // namespace
}  // namespace facetrack
