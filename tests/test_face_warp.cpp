// The CNN cascade's input (src/cnn/face_warp): the face texture in canonical space.

#include "data/profile/face_profiling.hpp"
#include "expression/face_warp.hpp"
#include "expression/update_net.hpp"
#include "facetrack/error.hpp"
#include "facetrack/face_model.hpp"
#include "model/internals.hpp"
#include "nn/cnn_model_data.hpp"
#include "test_support.hpp"

#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <fstream>

namespace facetrack {
namespace {

struct WarpScene {
    std::shared_ptr<const FaceModel> model = FaceModel::load(test::shippedFaceModel());
    expression::WarpLayout layout = expression::makeWarpLayout(model::dataOf(*model), fit::basisOf(model)->expressions);
    core::Camera camera = core::cameraFor(640, 480, 60.0, 0.0);
};

const WarpScene& scene() {
    static const WarpScene s;
    return s;
}

cv::Mat smoothTexture(int width, int height, unsigned seed) {
    cv::theRNG().state = seed;
    cv::Mat noise(height, width, CV_32F);
    cv::randn(noise, 0.0, 1.0);
    cv::Mat smooth;
    cv::GaussianBlur(noise, smooth, cv::Size(0, 0), 6.0);
    cv::normalize(smooth, smooth, 0, 255, cv::NORM_MINMAX);
    cv::Mat frame;
    smooth.convertTo(frame, CV_8U);
    return frame;
}

fit::FaceParams faceAt(const Eigen::Vector3d& eulerDeg, const Eigen::Vector3d& translation, Eigen::Index expressions) {
    fit::FaceParams params;
    params.pose.head<3>() = fit::omegaFromEuler(eulerDeg);
    params.pose.tail<3>() = translation;
    params.expression = Eigen::VectorXd::Zero(expressions);
    return params;
}

TEST(FaceWarp, LayoutCoversThePatchWithAnchorsSpreadOverTheFace) {
    const auto& l = scene().layout;
    EXPECT_EQ(l.size, 64);
    EXPECT_GT(l.anchorCount(), 100);
    EXPECT_LT(l.anchorCount(), 14 * 14 + 1);
    EXPECT_TRUE(std::all_of(l.pixel_triangle.begin(), l.pixel_triangle.end(), [](int t) { return t >= 0; }));
    EXPECT_GE(l.canonical.minCoeff(), -0.5 - 1e-9);
    EXPECT_LE(l.canonical.maxCoeff(), l.size - 0.5 + 1e-9);
    // The anchors span most of the patch: the face fills it.
    const Eigen::Matrix2Xd a = l.canonical.leftCols(l.anchorCount());
    EXPECT_GT(a.row(0).maxCoeff() - a.row(0).minCoeff(), 0.7 * l.size);
    EXPECT_GT(a.row(1).maxCoeff() - a.row(1).minCoeff(), 0.7 * l.size);
}

TEST(FaceWarp, PatchDoesNotChangeWhenTheCameraRollsAboutItsAxis) {
    // A smooth texture; the same face seen by a camera rolled by 20 degrees about its optical axis
    // is the image rotated about the principal point, and must give the same patch.
    const auto& s = scene();
    const cv::Mat frame = smoothTexture(640, 480, 2);
    const fit::FaceParams params = faceAt({8.0, -15.0, 5.0}, {1.0, -1.0, 50.0}, s.layout.anchors.expressionCount());
    cv::Mat patch;
    expression::warpFace(s.layout, frame, expression::projectAnchors(s.layout, {}, s.camera, params), patch);

    const double roll = 20.0;
    const Eigen::Matrix3d rz = Eigen::AngleAxisd(roll * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    fit::FaceParams rolled = params;
    rolled.pose.head<3>() = Eigen::AngleAxisd(rz * fit::rotationOf(params.omega())).angle() *
                            Eigen::AngleAxisd(rz * fit::rotationOf(params.omega())).axis();
    rolled.pose.tail<3>() = rz * params.translation();
    // The image under the rolled camera: each pixel moves about the principal point by the roll.
    const cv::Mat turn = cv::getRotationMatrix2D(cv::Point2f(static_cast<float>(s.camera.cx), static_cast<float>(s.camera.cy)), -roll, 1.0);
    cv::Mat rotatedFrame;
    cv::warpAffine(frame, rotatedFrame, turn, frame.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    cv::Mat rolledPatch;
    expression::warpFace(s.layout, rotatedFrame, expression::projectAnchors(s.layout, {}, s.camera, rolled), rolledPatch);

    cv::Mat difference;
    cv::absdiff(patch, rolledPatch, difference);
    EXPECT_LT(cv::mean(difference)[0], 2.0);
    // And the patch is not blank: it carries the texture.
    cv::Scalar mean, stddev;
    cv::meanStdDev(patch, mean, stddev);
    EXPECT_GT(stddev[0], 10.0);
}

TEST(FaceWarp, RejectsAWrongFrameOrAnchors) {
    const auto& s = scene();
    cv::Mat patch;
    const Eigen::Matrix2Xd anchors = Eigen::Matrix2Xd::Constant(2, s.layout.anchorCount(), 100.0);
    EXPECT_THROW(expression::warpFace(s.layout, cv::Mat(10, 10, CV_8UC3), anchors, patch), Error);
    EXPECT_THROW(expression::warpFace(s.layout, cv::Mat(10, 10, CV_8UC1), anchors.leftCols(3), patch), Error);
    Eigen::Matrix2Xd bad = anchors;
    bad(0, 0) = std::nan("");
    EXPECT_THROW(expression::warpFace(s.layout, cv::Mat(10, 10, CV_8UC1, cv::Scalar(7)), bad, patch), Error);
    // Anchors far outside a tiny frame: edge pixels repeated, no crash.
    expression::warpFace(s.layout, cv::Mat(1, 1, CV_8UC1, cv::Scalar(7)), anchors, patch);
    EXPECT_EQ(cv::countNonZero(patch != 7), 0);
}

TEST(CascadeUpdate, TakesTheStartToTheFaceAndTurnsAboutTheFaceCentre) {
    const auto& s = scene();
    const Eigen::Index e = s.layout.anchors.expressionCount();
    fit::FaceParams start = faceAt({5.0, 20.0, -3.0}, {2.0, 1.0, 45.0}, e), face = faceAt({-4.0, 32.0, 6.0}, {-1.0, 2.0, 50.0}, e);
    start.expression.setConstant(0.2);
    face.expression.setConstant(0.5);
    fit::FaceParams moved = start;
    expression::applyUpdate(s.layout, expression::updateBetween(s.layout, start, face), moved);
    EXPECT_LT((moved.pose - face.pose).norm(), 1e-9);
    EXPECT_LT((moved.expression - face.expression).norm(), 1e-12);
    // A pure turn leaves the face centre where it was: the update's rotation is about it.
    Eigen::VectorXd turn = Eigen::VectorXd::Zero(6 + e);
    turn.head<3>() = Eigen::Vector3d(0.1, -0.2, 0.05);
    fit::FaceParams turned = start;
    expression::applyUpdate(s.layout, turn, turned);
    const auto centre = [&](const fit::FaceParams& p) {
        return Eigen::Vector3d(fit::rotationOf(p.omega()) * s.layout.centre + p.translation());
    };
    EXPECT_LT((centre(turned) - centre(start)).norm(), 1e-9);
    EXPECT_GT((turned.translation() - start.translation()).norm(), 0.5);  // the model origin, behind the face, moved
    EXPECT_NEAR(expression::updateBetween(s.layout, start, turned).head<3>().norm(), turn.head<3>().norm(), 1e-9);
    // Expressions stay in [0, 1].
    Eigen::VectorXd push = Eigen::VectorXd::Zero(6 + e);
    push.tail(e).setConstant(2.0);
    expression::applyUpdate(s.layout, push, turned);
    EXPECT_EQ(turned.expression.maxCoeff(), 1.0);
}

TEST(FaceProfiling, TurnedFaceCarriesThePhotographsTextureAlong) {
    const auto& s = scene();
    const cv::Mat photo = smoothTexture(640, 480, 5);
    const fit::FaceParams photographed = faceAt({0.0, 15.0, 0.0}, {0.0, 0.0, 50.0}, 0);
    const std::vector<float> identity(static_cast<std::size_t>(s.model->identityCount()), 0.f);

    // Not turned: the same image.
    const auto same = profile::profileFace(*s.model, photo, s.camera, identity, {}, photographed, photographed);
    cv::Mat difference;
    cv::absdiff(same.image, photo, difference);
    EXPECT_LT(cv::mean(difference)[0], 0.5);
    EXPECT_LT(same.hidden_share, 0.03);  // vertices on the outline, rounded to a pixel behind it

    // Turned 30 deg further: a front-facing point seen in both views keeps its grey level.
    const fit::FaceParams turned = profile::turnedBy(photographed, 30.0);
    EXPECT_NEAR(fit::eulerDegrees(turned.omega()).y(), 45.0, 0.5);
    const auto face = profile::profileFace(*s.model, photo, s.camera, identity, {}, photographed, turned);
    EXPECT_LT(face.hidden_share, 0.15);
    const auto vertices = s.model->vertices({}, {});
    const auto pixelOf = [&](const fit::FaceParams& p, const Vec3& v) {
        return s.camera.project<double>(fit::rotationOf(p.omega()) * fit::modelToFrontal() * Eigen::Vector3d(v.x, v.y, v.z) / 10.0 +
                                        p.translation());
    };
    double error = 0.0;
    int points = 0;
    // Nose, the near eye, mouth (the far eye is behind the nose at 45 deg).
    for (const int landmark : {30, 33, 36, 39, 48, 51, 57, 62, 66}) {
        const auto& v = vertices[model::dataOf(*s.model).landmark_vertices[static_cast<std::size_t>(landmark)]];
        const Eigen::Vector2d from = pixelOf(photographed, v), to = pixelOf(turned, v);
        error += std::abs(double(face.image.at<std::uint8_t>(cv::Point(int(std::lround(to.x())), int(std::lround(to.y()))))) -
                          double(photo.at<std::uint8_t>(cv::Point(int(std::lround(from.x())), int(std::lround(from.y()))))));
        ++points;
    }
    EXPECT_LT(error / points, 4.0);
    // The image did change where the face is.
    cv::absdiff(face.image, photo, difference);
    EXPECT_GT(cv::mean(difference)[0], 1.0);
    EXPECT_THROW(profile::profileFace(*s.model, cv::Mat(), s.camera, identity, {}, photographed, turned), Error);
}

TEST(FaceProfiling, ExpressionCopiesMoveOneGroupOfShapesAndCarryTheTextureWithTheMesh) {
    const auto& s = scene();
    const cv::Mat photo = smoothTexture(640, 480, 9);
    const std::vector<std::string> names = {"browDown_L",    "browDown_R",    "browInnerUp_L", "browInnerUp_R",
                                            "browOuterUp_L", "browOuterUp_R", "mouthPucker",   "jawOpen"};
    const std::vector<int> ids = nn::expressionIndices(s.model->expressionNames(), names);
    fit::FaceParams label = faceAt({0.0, 10.0, 0.0}, {0.0, 0.0, 50.0}, static_cast<Eigen::Index>(ids.size()));
    label.expression << 0.1, 0.1, 0.0, 0.0, 0.2, 0.2, 0.0, 0.3;
    const std::vector<float> identity(static_cast<std::size_t>(s.model->identityCount()), 0.f);
    std::mt19937 rng(5);
    const auto copies = profile::expressionCopies(*s.model, photo, s.camera, identity, ids, label, 12, rng,
                                                  {"brows_down", "inner_brows_up", "brows_up", "pucker"});
    ASSERT_EQ(copies.size(), 12u);  // a frontal face hides nothing when its brows or lips move
    const std::vector<std::vector<int>> groups = {{0, 1}, {2, 3}, {2, 3, 4, 5}, {6}};  // positions in `names`
    const auto photographedMesh = s.model->vertices(identity, profile::nativeWeights(*s.model, ids, label.expression));
    const auto pixelOf = [&](const Vec3& v) {
        return s.camera.project<double>(fit::rotationOf(label.omega()) * fit::modelToFrontal() * Eigen::Vector3d(v.x, v.y, v.z) / 10.0 +
                                        label.translation());
    };
    double carried = 0.0, unmoved = 0.0;
    for (const auto& copy : copies) {
        EXPECT_EQ(copy.label.pose, label.pose);
        EXPECT_EQ(copy.label.expression[7], label.expression[7]);  // jawOpen is in no group
        // Exactly one group moved, all its shapes to one weight in [0, 0.9]; the others kept.
        int matching = 0;
        for (const auto& group : groups) {
            const double w = copy.label.expression[group[0]];
            bool isIt = w >= 0.0 && w <= 0.9;
            for (int k = 0; k < static_cast<int>(names.size()); ++k) {
                const bool in = std::find(group.begin(), group.end(), k) != group.end();
                isIt = isIt && (in ? copy.label.expression[k] == w : copy.label.expression[k] == label.expression[k]);
            }
            matching += isIt;
        }
        EXPECT_GE(matching, 1) << copy.label.expression.transpose();
        // A brow, an eye and the lips' points keep their grey level where the moved mesh puts them.
        const auto movedMesh = s.model->vertices(identity, profile::nativeWeights(*s.model, ids, copy.label.expression));
        double error = 0.0;
        for (const int landmark : {19, 24, 21, 39, 48, 51, 54, 57}) {
            const auto v = static_cast<std::size_t>(model::dataOf(*s.model).landmark_vertices[static_cast<std::size_t>(landmark)]);
            const Eigen::Vector2d from = pixelOf(photographedMesh[v]), to = pixelOf(movedMesh[v]);
            const auto grey = [](const cv::Mat& image, const Eigen::Vector2d& p) {
                return double(image.at<std::uint8_t>(cv::Point(int(std::lround(p.x())), int(std::lround(p.y())))));
            };
            error += std::abs(grey(copy.image, to) - grey(photo, from));
            if ((to - from).norm() > 2.0) {  // moved far enough for the photograph itself to differ there
                carried += std::abs(grey(copy.image, to) - grey(photo, from));
                unmoved += std::abs(grey(photo, to) - grey(photo, from));
            }
        }
        EXPECT_LT(error / 8.0, 4.0);
    }
    std::printf("points moved over 2 px: grey difference %.0f carried, %.0f had the image not moved\n", carried, unmoved);
    EXPECT_GT(unmoved, 100.0);  // the test's moves are visible in the texture
    EXPECT_LT(carried, 0.3 * unmoved);

    // Named groups: only those move.
    for (const auto& copy : profile::expressionCopies(*s.model, photo, s.camera, identity, ids, label, 6, rng, {"brows_down"})) {
        EXPECT_EQ(copy.label.expression[0], copy.label.expression[1]);
        EXPECT_EQ(copy.label.expression.tail(6), label.expression.tail(6));
    }
    EXPECT_THROW(profile::expressionCopies(*s.model, photo, s.camera, identity, ids, label, 1, rng, {"brows_sideways"}), Error);
}

TEST(FaceProfiling, ExpressionWarpingRaisesEveryShapeButThoseThatOpenTheMouthAndTakesCapturedFaces) {
    const auto& s = scene();
    const cv::Mat photo = smoothTexture(640, 480, 9);
    const std::vector<std::string> groups = profile::expressionCopyGroups(*s.model);
    for (const char* group : {"mouthFrown", "mouthFrown_L", "cheekPuff", "noseSneer_R", "jawLeft", "mouthPress", "pucker"})
        EXPECT_NE(std::find(groups.begin(), groups.end(), group), groups.end()) << group;
    for (const char* kept : {"jawOpen", "mouthUpperUp", "eyeLookUp_L", "eyeBlink"})
        EXPECT_EQ(std::find(groups.begin(), groups.end(), kept), groups.end()) << kept;

    const std::vector<std::string> names = {"mouthFrown_L", "mouthFrown_R", "jawOpen", "mouthPucker"};
    const std::vector<int> ids = nn::expressionIndices(s.model->expressionNames(), names);
    fit::FaceParams label = faceAt({0.0, 0.0, 0.0}, {0.0, 0.0, 50.0}, static_cast<Eigen::Index>(ids.size()));
    label.expression << 0.0, 0.0, 0.2, 0.0;
    const std::vector<float> identity(static_cast<std::size_t>(s.model->identityCount()), 0.f);
    std::mt19937 rng(3);
    // A pair's stem moves both sides alike, one side's name that side only.
    for (const auto& copy : profile::expressionCopies(*s.model, photo, s.camera, identity, ids, label, 3, rng, {"mouthFrown"}))
        EXPECT_EQ(copy.label.expression[0], copy.label.expression[1]);
    for (const auto& copy : profile::expressionCopies(*s.model, photo, s.camera, identity, ids, label, 3, rng, {"mouthFrown_L"}))
        EXPECT_EQ(copy.label.expression[1], 0.0);
    // A captured face replaces the photograph's weights, but the mouth opens no further than photographed.
    std::vector<float> captured(s.model->expressionNames().size(), 0.f);
    for (const int id : ids) captured[static_cast<std::size_t>(id)] = 0.7f;
    const auto copies = profile::expressionCopies(*s.model, photo, s.camera, identity, ids, label, 2, rng, {"captured"}, {captured});
    ASSERT_EQ(copies.size(), 2u);
    for (const auto& copy : copies) {
        EXPECT_NEAR(copy.label.expression[0], 0.7, 1e-6);
        EXPECT_NEAR(copy.label.expression[3], 0.7, 1e-6);
        EXPECT_NEAR(copy.label.expression[2], 0.2, 1e-6);  // jawOpen kept at the photograph's
        cv::Mat difference;
        cv::absdiff(copy.image, photo, difference);
        EXPECT_GT(cv::mean(difference)[0], 0.1);  // the mouth moved
    }
    EXPECT_THROW(profile::expressionCopies(*s.model, photo, s.camera, identity, ids, label, 1, rng, {"captured"}), Error);
}

TEST(FaceProfiling, ReadsArkitCapturesIntoTheFaceModelsOrder) {
    const auto& s = scene();
    const std::string dir = test::tempPath("arkit");
    std::filesystem::create_directories(dir);
    std::ofstream(dir + "/take.csv") << "Timecode,BlendShapeCount,MouthSmileLeft,JawOpen,TongueOut\n"
                                        "00:00:00:01.000,3,0.5,0.25,1.0\n00:00:00:02.000,3,1.5,0.0,0.0\n00:00:00:03.000,3,0.1\n";
    const auto faces = profile::readArkitCaptures(*s.model, dir);
    ASSERT_EQ(faces.size(), 2u);  // the cut last line is left out
    const auto& names = s.model->expressionNames();
    const auto at = [&](const std::string& n) {
        return static_cast<std::size_t>(std::find(names.begin(), names.end(), n) - names.begin());
    };
    EXPECT_FLOAT_EQ(faces[0][at("mouthSmile_L")], 0.5f);
    EXPECT_FLOAT_EQ(faces[0][at("jawOpen")], 0.25f);
    EXPECT_FLOAT_EQ(faces[0][at("mouthSmile_R")], 0.f);
    EXPECT_FLOAT_EQ(faces[1][at("mouthSmile_L")], 1.f);  // clamped to [0, 1]
    EXPECT_EQ(profile::readArkitCaptures(*s.model, dir, 2).size(), 1u);
    std::filesystem::remove_all(dir);
    EXPECT_THROW(profile::readArkitCaptures(*s.model, dir), std::exception);
}

TEST(FaceProfiling, TurnSequenceGoesOutByTheStepAndComesBack) {
    const auto& s = scene();
    const cv::Mat photo = smoothTexture(320, 240, 7);
    const fit::FaceParams photographed = faceAt({0.0, 30.0, 0.0}, {0.0, 0.0, 100.0}, 0);
    const std::vector<float> identity(static_cast<std::size_t>(s.model->identityCount()), 0.f);
    const auto frames = profile::turnSequence(*s.model, photo, s.camera, identity, {}, photographed, 10.0);
    std::vector<double> yaws;
    for (const auto& f : frames) {
        yaws.push_back(fit::eulerDegrees(f.label.omega()).y());
        EXPECT_EQ(f.image.size(), photo.size());
    }
    ASSERT_GE(yaws.size(), 5u);
    EXPECT_NEAR(yaws.front(), 30.0, 0.5);
    EXPECT_NEAR(yaws.back(), 30.0, 0.5);
    // Out the way it looks, 10 degrees a frame, as far as the head stays 85 % seen (at most 80), and back the same way.
    const auto far = std::max_element(yaws.begin(), yaws.end());
    EXPECT_GE(*far, 40.0 - 0.5);
    const auto hiddenAt = [&](double yaw) {
        return profile::profileFace(*s.model, photo, s.camera, identity, {}, photographed, profile::turnedBy(photographed, yaw - 30.0))
            .hidden_share;
    };
    EXPECT_LE(hiddenAt(*far), 0.15);
    if (*far + 10.0 <= 80.0) {
        EXPECT_GT(hiddenAt(*far + 10.0), 0.15);
    }
    for (auto y = yaws.begin(); y + 1 != yaws.end(); ++y) EXPECT_NEAR(std::abs(*(y + 1) - *y), 10.0, 0.5) << y - yaws.begin();
    for (auto up = yaws.begin(), down = far + (far - yaws.begin()); up != far; ++up, --down) EXPECT_NEAR(*up, *down, 1e-6);
    EXPECT_THROW(profile::turnSequence(*s.model, photo, s.camera, identity, {}, photographed, 0.1), Error);
}

}  // namespace
}  // namespace facetrack
