// The CNN cascade's input (src/cnn/face_warp): the face texture in canonical space.

#include "cnn/face_warp.hpp"
#include "facetrack/error.hpp"
#include "facetrack/face_model.hpp"
#include "test_support.hpp"

#include <opencv2/imgproc.hpp>

#include <random>

namespace facetrack {
namespace {

struct WarpScene {
    std::shared_ptr<const FaceModel> model = FaceModel::load(test::shippedFaceModel());
    cnn::WarpLayout layout = cnn::makeWarpLayout(model->data(), model->fitBasis()->expressions);
    fit::Camera camera = fit::cameraFor(640, 480, 60.0, 0.0);
};

const WarpScene& scene() {
    static const WarpScene s;
    return s;
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
    std::mt19937 rng(2);
    cv::Mat noise(480, 640, CV_32F);
    cv::randn(noise, 0.0, 1.0);
    cv::Mat smooth;
    cv::GaussianBlur(noise, smooth, cv::Size(0, 0), 6.0);
    cv::normalize(smooth, smooth, 0, 255, cv::NORM_MINMAX);
    cv::Mat frame;
    smooth.convertTo(frame, CV_8U);

    fit::FaceParams params;
    params.pose.head<3>() = fit::omegaFromEuler({8.0, -15.0, 5.0});
    params.pose.tail<3>() = Eigen::Vector3d(1.0, -1.0, 50.0);
    params.expression = Eigen::VectorXd::Zero(s.layout.anchors.expressionCount());
    cv::Mat patch;
    cnn::warpFace(s.layout, frame, cnn::projectAnchors(s.layout, {}, s.camera, params), patch);

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
    cnn::warpFace(s.layout, rotatedFrame, cnn::projectAnchors(s.layout, {}, s.camera, rolled), rolledPatch);

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
    EXPECT_THROW(cnn::warpFace(s.layout, cv::Mat(10, 10, CV_8UC3), anchors, patch), Error);
    EXPECT_THROW(cnn::warpFace(s.layout, cv::Mat(10, 10, CV_8UC1), anchors.leftCols(3), patch), Error);
    Eigen::Matrix2Xd bad = anchors;
    bad(0, 0) = std::nan("");
    EXPECT_THROW(cnn::warpFace(s.layout, cv::Mat(10, 10, CV_8UC1, cv::Scalar(7)), bad, patch), Error);
    // Anchors far outside a tiny frame: edge pixels repeated, no crash.
    cnn::warpFace(s.layout, cv::Mat(1, 1, CV_8UC1, cv::Scalar(7)), anchors, patch);
    EXPECT_EQ(cv::countNonZero(patch != 7), 0);
}

}  // namespace
}  // namespace facetrack
