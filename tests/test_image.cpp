#include "core/image.hpp"

#include "facetrack/error.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace facetrack::core {
namespace {

TEST(Image, InvalidViewsAreRejectedClearly) {
    const std::vector<std::uint8_t> pixels(64 * 48 * 3, 0);
    EXPECT_THROW(wrap(ImageView{nullptr, 64, 48, 64 * 3, PixelFormat::Bgr8}), Error);
    EXPECT_THROW(wrap(ImageView{pixels.data(), 0, 48, 64 * 3, PixelFormat::Bgr8}), Error);
    EXPECT_THROW(wrap(ImageView{pixels.data(), 64, -1, 64 * 3, PixelFormat::Bgr8}), Error);
    try {
        wrap(ImageView{pixels.data(), 64, 48, 64, PixelFormat::Bgr8});
        FAIL() << "a short stride was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("stride"), std::string::npos) << e.what();
    }
}

TEST(Image, FormatsConvertToTheSameBgrAndGray) {
    cv::Mat bgr(5, 7, CV_8UC3);
    cv::randu(bgr, 0, 255);
    cv::Mat rgb, bgra, rgba;
    cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
    cv::cvtColor(bgr, bgra, cv::COLOR_BGR2BGRA);
    cv::cvtColor(bgr, rgba, cv::COLOR_BGR2RGBA);
    const std::pair<cv::Mat, PixelFormat> inputs[] = {
        {bgr, PixelFormat::Bgr8}, {rgb, PixelFormat::Rgb8}, {bgra, PixelFormat::Bgra8}, {rgba, PixelFormat::Rgba8}};
    cv::Mat gray;
    cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
    for (const auto& [mat, format] : inputs) {
        const ImageView view{mat.data, mat.cols, mat.rows, mat.step[0], format};
        EXPECT_EQ(cv::norm(toBgr(view), bgr, cv::NORM_INF), 0.0);
        cv::Mat buffer;
        EXPECT_LE(cv::norm(toGray(view, buffer), gray, cv::NORM_INF), 1.0);
    }
}

// The Tracker keeps the grey frame and passes it back as the next buffer: a grey frame
// wrapped once must not be written into when a colour frame of the same size follows.
TEST(Image, AColourFrameAfterAGreyOneNeverWritesIntoTheGreyFramesPixels) {
    std::vector<std::uint8_t> grey(7 * 5, 7);
    cv::Mat gray = toGray({grey.data(), 7, 5, 7, PixelFormat::Gray8}, gray);
    EXPECT_EQ(gray.data, grey.data());
    const cv::Mat bgr(5, 7, CV_8UC3, cv::Scalar(200, 200, 200));
    gray = toGray(viewOf(bgr), gray);
    EXPECT_EQ(std::count(grey.begin(), grey.end(), std::uint8_t{7}), 35);
    EXPECT_EQ(gray.at<std::uint8_t>(2, 3), 200);
}

TEST(Image, StridedViewWrapsWithoutCopying) {
    cv::Mat big(10, 20, CV_8UC3, cv::Scalar(1, 2, 3));
    const cv::Mat roi = big(cv::Rect(2, 3, 8, 4));
    const ImageView view = viewOf(roi);
    EXPECT_EQ(view.stride, big.step[0]);
    const cv::Mat wrapped = wrap(view);
    EXPECT_EQ(wrapped.data, roi.data);
    EXPECT_EQ(wrapped.size(), roi.size());
}

// The refiners' patches were cut by cv::warpAffine when their nets were trained and measured; the
// by-hand warp must give the same bytes, at any scale, turn and shift, the frame's border included.
TEST(WarpAffineGray, GivesOpenCvsWarpAffineToTheByte) {
    cv::RNG rng(11);
    // The last frame is a view into a larger image (its rows' step longer than its width): where
    // the gathers of eight points run (AVX2), they must stay in the view's rows.
    cv::Mat larger(130, 175, CV_8UC1);
    rng.fill(larger, cv::RNG::UNIFORM, 0, 256);
    for (const cv::Size frameSize : {cv::Size(160, 120), cv::Size(7, 5), cv::Size(1, 1), cv::Size(1, 9), cv::Size(0, 0)}) {
        cv::Mat frame = frameSize.area() > 0 ? cv::Mat(frameSize, CV_8UC1) : larger(cv::Rect(9, 4, 150, 118));
        if (frameSize.area() > 0) rng.fill(frame, cv::RNG::UNIFORM, 0, 256);
        for (int k = 0; k < 150; ++k) {
            const double angle = rng.uniform(0.0, 2 * CV_PI), scale = std::exp(rng.uniform(std::log(0.2), std::log(4.0)));
            const double tx = rng.uniform(-60.0, frame.cols + 60.0), ty = rng.uniform(-60.0, frame.rows + 60.0);
            const cv::Matx23d a(scale * std::cos(angle), -scale * std::sin(angle) * rng.uniform(0.8, 1.2), tx,  //
                                scale * std::sin(angle), scale * std::cos(angle), ty);
            const cv::Size size = k % 3 == 0 ? cv::Size(96, 96) : k % 3 == 1 ? cv::Size(40, 28) : cv::Size(1, 1);
            cv::Mat expected, patch;
            cv::warpAffine(frame, expected, a, size, cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
            warpAffineGray(frame, a, size, patch);
            ASSERT_EQ(patch.size(), size);
            ASSERT_EQ(cv::norm(patch, expected, cv::NORM_INF), 0.0) << "frame " << frame.size() << ", map " << a << ", patch " << size;
        }
    }
    // The patch's buffer is reused; bad frames and sizes are errors.
    cv::Mat frame(20, 30, CV_8UC1, cv::Scalar(9)), patch(8, 8, CV_8UC1);
    const uchar* buffer = patch.data;
    warpAffineGray(frame, cv::Matx23d(1, 0, 2, 0, 1, 3), {8, 8}, patch);
    EXPECT_EQ(patch.data, buffer);
    EXPECT_EQ(cv::countNonZero(patch != 9), 0);
    EXPECT_THROW(warpAffineGray(cv::Mat(), cv::Matx23d(1, 0, 0, 0, 1, 0), {8, 8}, patch), Error);
    EXPECT_THROW(warpAffineGray(cv::Mat(4, 4, CV_8UC3), cv::Matx23d(1, 0, 0, 0, 1, 0), {8, 8}, patch), Error);
    EXPECT_THROW(warpAffineGray(frame, cv::Matx23d(1, 0, 0, 0, 1, 0), {0, 8}, patch), Error);
    // A map that is not finite gives a patch of the frame's pixels, not a crash.
    const double nan = std::numeric_limits<double>::quiet_NaN();
    warpAffineGray(frame, cv::Matx23d(nan, 0, 0, 0, 1, nan), {8, 8}, patch);
    EXPECT_EQ(cv::countNonZero(patch != 9), 0);
}

}  // namespace
}  // namespace facetrack::core
