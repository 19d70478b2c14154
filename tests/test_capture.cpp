// Camera capture: pixel conversion on buffers built here, and the messages a
// user gets when the camera is missing or wrong. No webcam is needed.

#include "capture/convert.hpp"
#include "facetrack/capture.hpp"
#include "facetrack/error.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <fstream>

namespace facetrack {
namespace {

/// BT.601 video range, the inverse of what webcams encode.
cv::Vec3b bt601ToBgr(int y, int u, int v) {
    const double c = 1.164 * (y - 16), d = u - 128.0, e = v - 128.0;
    const auto clamp = [](double x) { return static_cast<uchar>(std::clamp(std::lround(x), 0L, 255L)); };
    return {clamp(c + 2.018 * d), clamp(c - 0.391 * d - 0.813 * e), clamp(c + 1.596 * e)};
}

TEST(Capture, YuyvToBgrFollowsBt601IncludingRowPadding) {
    // 6x3 pixels, each pair of pixels its own (U, V), rows padded to 16 bytes.
    constexpr int w = 6, h = 3;
    constexpr std::size_t stride = 16;
    std::vector<std::uint8_t> yuyv(stride * h, 0xEE);
    const int samples[][4] = {{16, 128, 235, 128},  {81, 90, 145, 240},   {41, 240, 210, 16},
                              {126, 128, 126, 128}, {200, 60, 30, 200},   {170, 166, 106, 16},
                              {60, 100, 180, 150},  {235, 128, 16, 128},  {128, 16, 128, 240}};
    for (int r = 0; r < h; ++r) {
        for (int p = 0; p < w / 2; ++p) {
            const auto& s = samples[r * (w / 2) + p];
            std::uint8_t* q = &yuyv[r * stride + 4 * p];
            q[0] = s[0], q[1] = s[1], q[2] = s[2], q[3] = s[3];  // Y0 U Y1 V
        }
    }
    cv::Mat bgr;
    capture::yuyvToBgr(yuyv.data(), yuyv.size(), w, h, stride, bgr);
    ASSERT_EQ(bgr.type(), CV_8UC3);
    ASSERT_EQ(bgr.size(), cv::Size(w, h));
    for (int r = 0; r < h; ++r) {
        for (int p = 0; p < w / 2; ++p) {
            const auto& s = samples[r * (w / 2) + p];
            for (int k = 0; k < 2; ++k) {
                const cv::Vec3b expected = bt601ToBgr(s[2 * k], s[1], s[3]);
                const cv::Vec3b got = bgr.at<cv::Vec3b>(r, 2 * p + k);
                for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], expected[c], 2) << "row " << r << " pixel " << 2 * p + k;
            }
        }
    }
    // Black, white and mid grey land where they should.
    EXPECT_LE(bgr.at<cv::Vec3b>(0, 0)[0], 1);
    EXPECT_GE(bgr.at<cv::Vec3b>(0, 1)[1], 254);
    EXPECT_NEAR(bgr.at<cv::Vec3b>(1, 0)[2], 128, 2);
}

TEST(Capture, YuyvRejectsShortBuffersAndOddWidths) {
    std::vector<std::uint8_t> yuyv(4 * 2 * 3 - 1);
    cv::Mat bgr;
    EXPECT_THROW(capture::yuyvToBgr(yuyv.data(), yuyv.size(), 4, 3, 8, bgr), Error);
    EXPECT_THROW(capture::yuyvToBgr(yuyv.data(), yuyv.size(), 3, 2, 6, bgr), Error);
    EXPECT_THROW(capture::yuyvToBgr(yuyv.data(), yuyv.size(), 4, 2, 6, bgr), Error);  // stride < 2 * width
}

cv::Mat testPattern() {
    cv::Mat image(48, 64, CV_8UC3);
    for (int y = 0; y < image.rows; ++y) {
        for (int x = 0; x < image.cols; ++x) image.at<cv::Vec3b>(y, x) = cv::Vec3b(x * 4, y * 5, 255 - x * 2);
    }
    cv::circle(image, {32, 24}, 10, cv::Scalar(20, 220, 40), -1);
    return image;
}

/// The JPEG without its DHT segments, as many webcams send MJPEG frames.
std::vector<std::uint8_t> withoutHuffmanTables(const std::vector<std::uint8_t>& jpeg) {
    std::vector<std::uint8_t> out(jpeg.begin(), jpeg.begin() + 2);
    std::size_t i = 2;
    while (i + 4 <= jpeg.size() && jpeg[i] == 0xFF && jpeg[i + 1] != 0xDA) {
        const std::size_t length = (jpeg[i + 2] << 8) | jpeg[i + 3];
        if (jpeg[i + 1] != 0xC4) out.insert(out.end(), jpeg.begin() + i, jpeg.begin() + i + 2 + length);
        i += 2 + length;
    }
    out.insert(out.end(), jpeg.begin() + i, jpeg.end());
    return out;
}

TEST(Capture, MjpegDecodesFramesWithAndWithoutHuffmanTables) {
    const cv::Mat original = testPattern();
    std::vector<std::uint8_t> jpeg;
    ASSERT_TRUE(cv::imencode(".jpg", original, jpeg, {cv::IMWRITE_JPEG_QUALITY, 95}));
    cv::Mat bgr;
    ASSERT_TRUE(capture::decodeMjpeg(jpeg.data(), jpeg.size(), 64, 48, bgr));
    EXPECT_GT(cv::PSNR(bgr, original), 25.0);  // 4:2:0 chroma on a sharp pattern

    const auto stripped = withoutHuffmanTables(jpeg);
    ASSERT_LT(stripped.size(), jpeg.size()) << "the test JPEG had no DHT segment to strip";
    cv::Mat fromStripped;
    ASSERT_TRUE(capture::decodeMjpeg(stripped.data(), stripped.size(), 64, 48, fromStripped));
    EXPECT_EQ(cv::norm(fromStripped, bgr, cv::NORM_INF), 0.0);  // the standard tables are the ones the encoder used
}

TEST(Capture, MjpegRejectsTornGarbageAndWrongSizedFrames) {
    std::vector<std::uint8_t> jpeg;
    ASSERT_TRUE(cv::imencode(".jpg", testPattern(), jpeg));
    cv::Mat bgr;
    EXPECT_FALSE(capture::decodeMjpeg(jpeg.data(), jpeg.size(), 640, 480, bgr));  // not the negotiated size
    EXPECT_FALSE(capture::decodeMjpeg(jpeg.data(), 3, 64, 48, bgr));
    const std::vector<std::uint8_t> garbage(1000, 0x5A);
    EXPECT_FALSE(capture::decodeMjpeg(garbage.data(), garbage.size(), 64, 48, bgr));
    std::vector<std::uint8_t> header(jpeg.begin(), jpeg.begin() + 200);  // SOI and tables, no image data
    EXPECT_FALSE(capture::decodeMjpeg(header.data(), header.size(), 64, 48, bgr));
    EXPECT_FALSE(capture::decodeMjpeg(nullptr, 0, 64, 48, bgr));
}

std::string openError(const CaptureSettings& settings) {
    try {
        CameraCapture camera(settings);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

TEST(Capture, MissingDeviceSaysWhichDevicesExist) {
    const std::string message = openError({"/dev/video_facetrack_missing"});
    EXPECT_NE(message.find("no camera '/dev/video_facetrack_missing'"), std::string::npos) << message;
    const bool listed = message.find("devices present: /dev/video") != std::string::npos;
    const bool none = message.find("no /dev/video* devices exist") != std::string::npos;
    EXPECT_EQ(listed, !CameraCapture::listDevices().empty()) << message;
    EXPECT_EQ(none, CameraCapture::listDevices().empty()) << message;
}

TEST(Capture, FilesAndNonVideoDevicesAreRefusedClearly) {
    const auto file = std::filesystem::temp_directory_path() / "facetrack_not_a_camera";
    std::ofstream(file) << "x";
    EXPECT_NE(openError({file.string()}).find("is not a device node"), std::string::npos);
    std::filesystem::remove(file);
    EXPECT_NE(openError({"/dev/null"}).find("is not a V4L2 video device"), std::string::npos) << openError({"/dev/null"});
    CaptureSettings bad;
    bad.width = 0;
    EXPECT_NE(openError(bad).find("must be positive"), std::string::npos);
}

TEST(Capture, FrameViewDescribesItsPixels) {
    CapturedFrame frame;
    frame.width = 4;
    frame.height = 2;
    frame.bgr.assign(4 * 2 * 3, 7);
    const ImageView view = frame.view();
    EXPECT_EQ(view.data, frame.bgr.data());
    EXPECT_EQ(view.stride, 12u);
    EXPECT_EQ(view.format, PixelFormat::Bgr8);
    EXPECT_EQ(toString(CaptureFormat::Mjpeg), "mjpeg");
}

}  // namespace
}  // namespace facetrack
