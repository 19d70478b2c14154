#include "core/image.hpp"

#include "facetrack/error.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

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

TEST(Image, StridedViewWrapsWithoutCopying) {
    cv::Mat big(10, 20, CV_8UC3, cv::Scalar(1, 2, 3));
    const cv::Mat roi = big(cv::Rect(2, 3, 8, 4));
    const ImageView view = viewOf(roi);
    EXPECT_EQ(view.stride, big.step[0]);
    const cv::Mat wrapped = wrap(view);
    EXPECT_EQ(wrapped.data, roi.data);
    EXPECT_EQ(wrapped.size(), roi.size());
}

}  // namespace
}  // namespace facetrack::core
