// Camera capture: pixel conversion on buffers built here, and the messages a
// user gets when the camera is missing or wrong. No webcam is needed.

#include "capture/convert.hpp"
#include "capture/video_device.hpp"
#include "facetrack/capture.hpp"
#include "facetrack/error.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <linux/videodev2.h>
#include <poll.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstring>
#include <deque>
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
    const int samples[][4] = {{16, 128, 235, 128}, {81, 90, 145, 240},  {41, 240, 210, 16},  {126, 128, 126, 128}, {200, 60, 30, 200},
                              {170, 166, 106, 16}, {60, 100, 180, 150}, {235, 128, 16, 128}, {128, 16, 128, 240}};
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

#if FACETRACK_WITH_V4L2

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
    const auto file = std::filesystem::path(test::tempPath("not_a_camera"));
    std::ofstream(file) << "x";
    EXPECT_NE(openError({file.string()}).find("is not a device node"), std::string::npos);
    std::filesystem::remove(file);
    EXPECT_NE(openError({"/dev/null"}).find("is not a V4L2 video device"), std::string::npos) << openError({"/dev/null"});
    CaptureSettings bad;
    bad.width = 0;
    EXPECT_NE(openError(bad).find("must be positive"), std::string::npos);
}

/// A scripted V4L2 camera: negotiates like a UVC driver, streams what the
/// script says (frames, silence, an unplug) through "mapped" buffers.
class FakeCamera final : public capture::VideoDevice {
public:
    enum class Event { Frame, Silence, Unplug };
    std::vector<std::uint32_t> formats = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_MJPEG};
    int max_width = 1280, max_height = 720;
    bool busy = false;
    std::deque<std::pair<Event, std::vector<std::uint8_t>>> script;

    bool opened = false;
    int mapped = 0;

    int open(const std::string&) override {
        opened = true;
        return 42;
    }
    void close(int) override { opened = false; }
    void* mmap(std::size_t length, int, std::int64_t offset) override {
        ++mapped;
        return buffers_.at(static_cast<std::size_t>(offset) / length).data();
    }
    void munmap(void*, std::size_t) override { --mapped; }
    int poll(int, int, short& revents) override {
        if (script.empty()) return 0;  // nothing comes: the caller's timeout
        auto [event, payload] = script.front();
        script.pop_front();
        if (event == Event::Silence) return 0;
        if (event == Event::Unplug) {
            unplugged_ = true;
            revents = POLLERR;
            return 1;
        }
        pending_ = payload;
        revents = POLLIN;
        return 1;
    }
    int ioctl(int, unsigned long request, void* arg) override {
        if (unplugged_) return fail(ENODEV);
        switch (request) {
            case VIDIOC_QUERYCAP: {
                auto* cap = static_cast<v4l2_capability*>(arg);
                std::strcpy(reinterpret_cast<char*>(cap->card), "Fake Cam");
                cap->capabilities = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
                return 0;
            }
            case VIDIOC_ENUM_FMT: {
                auto* desc = static_cast<v4l2_fmtdesc*>(arg);
                if (desc->index >= formats.size()) return fail(EINVAL);
                desc->pixelformat = formats[desc->index];
                return 0;
            }
            case VIDIOC_S_FMT: {
                if (busy) return fail(EBUSY);
                auto& pix = static_cast<v4l2_format*>(arg)->fmt.pix;
                if (std::find(formats.begin(), formats.end(), pix.pixelformat) == formats.end()) pix.pixelformat = formats[0];
                pix.width = std::min<std::uint32_t>(pix.width, max_width);
                pix.height = std::min<std::uint32_t>(pix.height, max_height);
                pix.bytesperline = pix.pixelformat == V4L2_PIX_FMT_YUYV ? 2 * pix.width : 0;
                size_ = 2 * pix.width * pix.height;
                return 0;
            }
            case VIDIOC_S_PARM:
                return 0;
            case VIDIOC_REQBUFS:
                static_cast<v4l2_requestbuffers*>(arg)->count = 4;
                buffers_.assign(4, std::vector<std::uint8_t>(size_));
                return 0;
            case VIDIOC_QUERYBUF: {
                auto* buf = static_cast<v4l2_buffer*>(arg);
                buf->length = static_cast<std::uint32_t>(size_);
                buf->m.offset = buf->index * static_cast<std::uint32_t>(size_);
                return 0;
            }
            case VIDIOC_QBUF:
                queued_.push_back(static_cast<v4l2_buffer*>(arg)->index);
                return 0;
            case VIDIOC_STREAMON:
            case VIDIOC_STREAMOFF:
                return 0;
            case VIDIOC_DQBUF: {
                if (queued_.empty()) return fail(EAGAIN);
                auto* buf = static_cast<v4l2_buffer*>(arg);
                buf->index = queued_.front();
                queued_.pop_front();
                auto& memory = buffers_[buf->index];
                std::copy_n(pending_.begin(), std::min(pending_.size(), memory.size()), memory.begin());
                buf->bytesused = static_cast<std::uint32_t>(std::min(pending_.size(), memory.size()));
                return 0;
            }
            default:
                return fail(EINVAL);
        }
    }

private:
    static int fail(int error) {
        errno = error;
        return -1;
    }
    std::size_t size_ = 0;
    std::vector<std::vector<std::uint8_t>> buffers_;
    std::deque<std::uint32_t> queued_;
    std::vector<std::uint8_t> pending_;
    bool unplugged_ = false;
};

/// A uniform YUYV frame.
std::vector<std::uint8_t> yuyvFrame(int width, int height, std::uint8_t y, std::uint8_t u, std::uint8_t v) {
    std::vector<std::uint8_t> frame(static_cast<std::size_t>(width) * height * 2);
    for (std::size_t i = 0; i < frame.size(); i += 4) frame[i] = y, frame[i + 1] = u, frame[i + 2] = y, frame[i + 3] = v;
    return frame;
}

// /dev/null passes the "is it a character device" check; the fake answers the rest.
CaptureSettings fakeSettings(int width = 640, int height = 480) {
    CaptureSettings s;
    s.device = "/dev/null";
    s.width = width;
    s.height = height;
    s.timeout_ms = 200;
    return s;
}

TEST(CaptureStream, NegotiatesStreamsAndConvertsYuyvFrames) {
    auto fake = std::make_shared<FakeCamera>();
    fake->script = {{FakeCamera::Event::Frame, yuyvFrame(640, 480, 126, 128, 128)},
                    {FakeCamera::Event::Frame, yuyvFrame(640, 480, 16, 128, 128)}};
    CameraCapture camera(fakeSettings(), fake);
    EXPECT_EQ(camera.format(), CaptureFormat::Yuyv);
    EXPECT_EQ(camera.description(), "Fake Cam (/dev/null): YUYV 640x480 at 30 fps");
    EXPECT_EQ(fake->mapped, 4);
    CapturedFrame frame;
    ASSERT_EQ(camera.read(frame), CaptureStatus::Frame);
    EXPECT_EQ(frame.width, 640);
    EXPECT_EQ(frame.height, 480);
    EXPECT_EQ(frame.sequence, 1u);
    EXPECT_NEAR(frame.bgr[3 * (240 * 640 + 320)], 128, 2);
    const std::uint8_t* before = frame.bgr.data();
    ASSERT_EQ(camera.read(frame), CaptureStatus::Frame);
    EXPECT_EQ(frame.bgr.data(), before) << "the frame buffer should be reused";
    EXPECT_EQ(frame.sequence, 2u);
    EXPECT_LE(frame.bgr[0], 1);
    EXPECT_EQ(camera.read(frame), CaptureStatus::Timeout);  // the script ran out
}

TEST(CaptureStream, AutoFormatWeighsDecodingAgainstBandwidth) {
    auto both = std::make_shared<FakeCamera>();
    EXPECT_EQ(CameraCapture(fakeSettings(640, 480), both).format(), CaptureFormat::Yuyv);
    EXPECT_EQ(CameraCapture(fakeSettings(1280, 720), both).format(), CaptureFormat::Mjpeg);
    auto mjpegOnly = std::make_shared<FakeCamera>();
    mjpegOnly->formats = {V4L2_PIX_FMT_MJPEG};
    EXPECT_EQ(CameraCapture(fakeSettings(640, 480), mjpegOnly).format(), CaptureFormat::Mjpeg);
    auto small = std::make_shared<FakeCamera>();
    small->max_width = 320, small->max_height = 240;
    const CameraCapture nearest(fakeSettings(640, 480), small);
    EXPECT_EQ(nearest.width(), 320);  // the driver's nearest size is what we report
    EXPECT_EQ(nearest.height(), 240);
}

TEST(CaptureStream, DropsCorruptMjpegFramesAndDeliversTheNextGoodOne) {
    auto fake = std::make_shared<FakeCamera>();
    fake->formats = {V4L2_PIX_FMT_MJPEG};
    cv::Mat image(480, 640, CV_8UC3, cv::Scalar(30, 140, 220));
    std::vector<std::uint8_t> jpeg;
    ASSERT_TRUE(cv::imencode(".jpg", image, jpeg));
    std::vector<std::uint8_t> torn(jpeg.begin(), jpeg.begin() + jpeg.size() / 2);
    fake->script = {
        {FakeCamera::Event::Frame, torn}, {FakeCamera::Event::Frame, std::vector<std::uint8_t>(500, 0)}, {FakeCamera::Event::Frame, jpeg}};
    CameraCapture camera(fakeSettings(), fake);
    CapturedFrame frame;
    ASSERT_EQ(camera.read(frame), CaptureStatus::Frame);
    EXPECT_EQ(frame.sequence, 1u);
    EXPECT_NEAR(frame.bgr[2], 220, 4);  // red channel of the good frame
}

std::string fakeOpenError(const std::shared_ptr<FakeCamera>& fake) {
    try {
        CameraCapture camera(fakeSettings(), fake);
    } catch (const Error& e) {
        EXPECT_FALSE(fake->opened) << "the device should be closed after a failed open";
        return e.what();
    }
    return "";
}

TEST(CaptureStream, UnsupportedFormatsAndBusyDevicesSayWhatToDo) {
    auto h264 = std::make_shared<FakeCamera>();
    h264->formats = {v4l2_fourcc('H', '2', '6', '4'), v4l2_fourcc('G', 'R', 'E', 'Y')};
    const std::string unsupported = fakeOpenError(h264);
    EXPECT_NE(unsupported.find("does not offer YUYV or MJPEG; it offers: H264 GREY"), std::string::npos) << unsupported;
    EXPECT_NE(unsupported.find("v4l2-ctl -d /dev/null --list-formats-ext"), std::string::npos) << unsupported;

    auto busy = std::make_shared<FakeCamera>();
    busy->busy = true;
    const std::string message = fakeOpenError(busy);
    EXPECT_NE(message.find("is busy: another program is using it"), std::string::npos) << message;
}

TEST(CaptureStream, UnplugIsReportedAndReleasesTheDevice) {
    auto fake = std::make_shared<FakeCamera>();
    fake->script = {
        {FakeCamera::Event::Frame, yuyvFrame(640, 480, 126, 128, 128)}, {FakeCamera::Event::Silence, {}}, {FakeCamera::Event::Unplug, {}}};
    CameraCapture camera(fakeSettings(), fake);
    CapturedFrame frame;
    EXPECT_EQ(camera.read(frame), CaptureStatus::Frame);
    EXPECT_EQ(camera.read(frame), CaptureStatus::Timeout);
    EXPECT_EQ(camera.read(frame), CaptureStatus::Disconnected);
    EXPECT_FALSE(fake->opened);
    EXPECT_EQ(fake->mapped, 0);
    EXPECT_EQ(camera.read(frame), CaptureStatus::Disconnected);  // and stays so, without touching the device
}

#else

TEST(Capture, WithoutV4l2OpeningSaysCaptureIsNotInTheBuild) {
    try {
        CameraCapture camera(CaptureSettings{});
        ADD_FAILURE() << "opened a camera in a build without V4L2";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("FACETRACK_WITH_V4L2=OFF"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(CameraCapture::listDevices().empty());
}

#endif  // FACETRACK_WITH_V4L2

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
