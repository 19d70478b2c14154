// CameraCapture: V4L2 streaming capture through libv4l2 (which smooths over
// driver quirks; its own format conversion is switched off, we convert).

#include "facetrack/capture.hpp"

#include "capture/convert.hpp"
#include "capture/video_device.hpp"
#include "facetrack/error.hpp"

#include <linux/videodev2.h>

#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>

namespace facetrack {

namespace {

constexpr int kBufferCount = 4;

std::string fourccName(std::uint32_t code) {
    std::string name;
    for (int i = 0; i < 4; ++i) name += static_cast<char>((code >> (8 * i)) & 0xFF);
    while (!name.empty() && name.back() == ' ') name.pop_back();
    return name;
}

std::uint32_t fourccOf(CaptureFormat format) { return format == CaptureFormat::Mjpeg ? V4L2_PIX_FMT_MJPEG : V4L2_PIX_FMT_YUYV; }

std::string presentDevices() {
    const auto devices = CameraCapture::listDevices();
    if (devices.empty()) return "no /dev/video* devices exist (no webcam plugged in, or no driver for it)";
    std::string list = "devices present:";
    for (const auto& d : devices) list += " " + d;
    return list;
}

bool isGone(int error) { return error == ENODEV || error == ENXIO || error == EIO; }

}  // namespace

std::vector<std::string> CameraCapture::listDevices() {
    std::vector<std::string> devices;
    std::error_code ec;
    for (const auto& entry : std::filesystem::directory_iterator("/dev", ec)) {
        const std::string name = entry.path().filename().string();
        if (name.rfind("video", 0) == 0) devices.push_back(entry.path().string());
    }
    std::sort(devices.begin(), devices.end());
    return devices;
}

struct CameraCapture::Impl {
    struct Buffer {
        void* start = MAP_FAILED;
        std::size_t length = 0;
    };

    std::shared_ptr<capture::VideoDevice> io;
    std::string device;
    std::string card;
    int fd = -1;
    int width = 0, height = 0;
    std::size_t stride = 0;
    double fps = 0.0;
    CaptureFormat format = CaptureFormat::Yuyv;
    int timeout_ms = 2000;
    std::vector<Buffer> buffers;
    bool streaming = false;
    std::uint64_t sequence = 0;
    std::chrono::steady_clock::time_point opened = std::chrono::steady_clock::now();
    cv::Mat decoded;  // reused between frames

    explicit Impl(std::shared_ptr<capture::VideoDevice> calls) : io(std::move(calls)) {}
    ~Impl() { close(); }

    /// ioctl that retries when interrupted by a signal.
    int xioctl(unsigned long request, void* arg) {
        int r;
        do {
            r = io->ioctl(fd, request, arg);
        } while (r == -1 && errno == EINTR);
        return r;
    }

    void close() {
        if (fd < 0) return;
        if (streaming) {
            v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
            xioctl(VIDIOC_STREAMOFF, &type);
        }
        for (auto& b : buffers) {
            if (b.start != MAP_FAILED) io->munmap(b.start, b.length);
        }
        buffers.clear();
        io->close(fd);
        fd = -1;
    }

    [[noreturn]] void fail(const std::string& what, int error) {
        const std::string cause = std::strerror(error);
        close();
        if (error == EBUSY) {
            throw Error("camera " + device + " is busy: another program is using it (close it, or find it with 'fuser " + device + "')");
        }
        if (isGone(error)) throw Error("camera " + device + " went away while " + what + " (unplugged?)");
        throw Error("camera " + device + ": " + what + " failed: " + cause);
    }

    void open(const CaptureSettings& s) {
        device = s.device;
        timeout_ms = s.timeout_ms;
        if (s.width <= 0 || s.height <= 0 || !(s.fps > 0.0) || s.timeout_ms <= 0) {
            throw Error("camera " + device + ": width, height, fps and timeout must be positive");
        }
        struct stat st {};
        if (::stat(device.c_str(), &st) != 0) throw Error("no camera '" + device + "': " + presentDevices());
        if (!S_ISCHR(st.st_mode)) throw Error("'" + device + "' is not a device node; " + presentDevices());

        fd = io->open(device);
        if (fd < 0) {
            const int error = errno;
            if (error == EACCES || error == EPERM) {
                throw Error("no permission to open " + device +
                            ": add yourself to the 'video' group (sudo usermod -aG video $USER, then log in again)");
            }
            if (error == ENOTTY) throw Error("'" + device + "' is not a V4L2 video device; " + presentDevices());
            if (error == EBUSY) fail("opening", error);
            throw Error("cannot open " + device + ": " + std::strerror(error) + "; " + presentDevices());
        }
        v4l2_capability cap{};
        if (xioctl(VIDIOC_QUERYCAP, &cap) != 0) {
            close();
            throw Error("'" + device + "' is not a V4L2 video device; " + presentDevices());
        }
        card = reinterpret_cast<const char*>(cap.card);
        const std::uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
        if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) {
            close();
            throw Error(device + " (" + card + ") does not capture video (webcams often add a metadata node: try the " +
                        "other /dev/video*); " + presentDevices());
        }
        if (!(caps & V4L2_CAP_STREAMING)) {
            close();
            throw Error(device + " (" + card + ") does not support streaming I/O, which facetrack needs");
        }

        negotiateFormat(s);
        setFrameRate(s.fps);
        mapBuffers();
        startStreaming();
    }

    std::vector<std::uint32_t> offeredFormats() {
        std::vector<std::uint32_t> formats;
        v4l2_fmtdesc desc{};
        desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        for (desc.index = 0; xioctl(VIDIOC_ENUM_FMT, &desc) == 0; ++desc.index) formats.push_back(desc.pixelformat);
        return formats;
    }

    void negotiateFormat(const CaptureSettings& s) {
        const auto offered = offeredFormats();
        const auto has = [&](CaptureFormat f) { return std::find(offered.begin(), offered.end(), fourccOf(f)) != offered.end(); };
        CaptureFormat chosen = s.format;
        if (chosen == CaptureFormat::Auto) {
            // YUYV needs no decoding but 2 bytes per pixel over USB: above
            // VGA, webcams only reach full rate in MJPEG.
            const bool large = s.width * s.height > 640 * 480;
            const CaptureFormat first = large ? CaptureFormat::Mjpeg : CaptureFormat::Yuyv;
            const CaptureFormat second = large ? CaptureFormat::Yuyv : CaptureFormat::Mjpeg;
            chosen = has(first) ? first : second;
        }
        if (!has(chosen)) {
            std::string list;
            for (auto f : offered) {
                list += ' ';
                list += fourccName(f);
            }
            close();
            throw Error(device + " (" + card + ") does not offer " +
                        (s.format == CaptureFormat::Auto ? std::string("YUYV or MJPEG") : fourccName(fourccOf(chosen))) + "; it offers:" +
                        (list.empty() ? std::string(" nothing") : list) + " (see 'v4l2-ctl -d " + device + " --list-formats-ext')");
        }

        v4l2_format fmt{};
        fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        fmt.fmt.pix.width = static_cast<std::uint32_t>(s.width);
        fmt.fmt.pix.height = static_cast<std::uint32_t>(s.height);
        fmt.fmt.pix.pixelformat = fourccOf(chosen);
        fmt.fmt.pix.field = V4L2_FIELD_ANY;
        if (xioctl(VIDIOC_S_FMT, &fmt) != 0) fail("setting the format", errno);
        if (fmt.fmt.pix.pixelformat != fourccOf(chosen)) {
            const std::string got = fourccName(fmt.fmt.pix.pixelformat);
            close();
            throw Error(device + " switched to format " + got + " instead of " + fourccName(fourccOf(chosen)));
        }
        format = chosen;
        width = static_cast<int>(fmt.fmt.pix.width);
        height = static_cast<int>(fmt.fmt.pix.height);
        stride = fmt.fmt.pix.bytesperline ? fmt.fmt.pix.bytesperline : static_cast<std::size_t>(width) * 2;
        if (width <= 0 || height <= 0 || (format == CaptureFormat::Yuyv && width % 2 != 0)) {
            close();
            throw Error(device + " negotiated an unusable size " + std::to_string(width) + "x" + std::to_string(height));
        }
    }

    void setFrameRate(double requested) {
        v4l2_streamparm parm{};
        parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        parm.parm.capture.timeperframe.numerator = 1000;
        parm.parm.capture.timeperframe.denominator = static_cast<std::uint32_t>(std::lround(requested * 1000.0));
        // Not every driver lets the rate be set; then it runs at its own.
        if (xioctl(VIDIOC_S_PARM, &parm) == 0 && parm.parm.capture.timeperframe.numerator > 0) {
            fps = static_cast<double>(parm.parm.capture.timeperframe.denominator) / parm.parm.capture.timeperframe.numerator;
        } else {
            fps = requested;
        }
    }

    void mapBuffers() {
        v4l2_requestbuffers req{};
        req.count = kBufferCount;
        req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        req.memory = V4L2_MEMORY_MMAP;
        if (xioctl(VIDIOC_REQBUFS, &req) != 0) fail("requesting buffers", errno);
        if (req.count < 2) {
            close();
            throw Error(device + " granted only " + std::to_string(req.count) + " buffer(s); at least 2 are needed");
        }
        buffers.resize(req.count);
        for (std::uint32_t i = 0; i < req.count; ++i) {
            v4l2_buffer buf{};
            buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
            buf.memory = V4L2_MEMORY_MMAP;
            buf.index = i;
            if (xioctl(VIDIOC_QUERYBUF, &buf) != 0) fail("querying buffers", errno);
            buffers[i].length = buf.length;
            buffers[i].start = io->mmap(buf.length, fd, buf.m.offset);
            if (buffers[i].start == MAP_FAILED) fail("mapping buffers", errno);
        }
    }

    void startStreaming() {
        for (std::uint32_t i = 0; i < buffers.size(); ++i) {
            v4l2_buffer buf{};
            buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
            buf.memory = V4L2_MEMORY_MMAP;
            buf.index = i;
            if (xioctl(VIDIOC_QBUF, &buf) != 0) fail("queueing buffers", errno);
        }
        v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        if (xioctl(VIDIOC_STREAMON, &type) != 0) fail("starting the stream", errno);
        streaming = true;
        opened = std::chrono::steady_clock::now();
    }

    CaptureStatus read(CapturedFrame& frame) {
        if (fd < 0) return CaptureStatus::Disconnected;
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
        for (;;) {
            const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
            if (left.count() <= 0) return CaptureStatus::Timeout;
            short revents = 0;
            const int ready = io->poll(fd, static_cast<int>(left.count()), revents);
            if (ready < 0) {
                if (errno == EINTR) continue;
                return disconnected();
            }
            if (ready == 0) return CaptureStatus::Timeout;
            if (revents & (POLLERR | POLLHUP | POLLNVAL)) return disconnected();

            v4l2_buffer buf{};
            buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
            buf.memory = V4L2_MEMORY_MMAP;
            if (xioctl(VIDIOC_DQBUF, &buf) != 0) {
                if (errno == EAGAIN) continue;
                return disconnected();
            }
            const bool ok = convert(buffers[buf.index], buf.bytesused, buf.flags, frame);
            if (xioctl(VIDIOC_QBUF, &buf) != 0) return disconnected();
            if (ok) return CaptureStatus::Frame;
        }
    }

    CaptureStatus disconnected() {
        close();
        return CaptureStatus::Disconnected;
    }

    /// False for a frame to drop (flagged as an error by the driver, or undecodable).
    bool convert(const Buffer& b, std::size_t used, std::uint32_t flags, CapturedFrame& frame) {
        if (flags & V4L2_BUF_FLAG_ERROR) return false;
        const auto* data = static_cast<const std::uint8_t*>(b.start);
        used = std::min(used, b.length);
        frame.width = width;
        frame.height = height;
        frame.bgr.resize(static_cast<std::size_t>(width) * height * 3);
        cv::Mat out(height, width, CV_8UC3, frame.bgr.data());
        if (format == CaptureFormat::Yuyv) {
            if (used < stride * static_cast<std::size_t>(height - 1) + static_cast<std::size_t>(width) * 2) return false;
            capture::yuyvToBgr(data, used, width, height, stride, out);
        } else {
            if (!capture::decodeMjpeg(data, used, width, height, decoded)) return false;
            decoded.copyTo(out);
        }
        frame.sequence = ++sequence;
        frame.timestamp_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - opened).count();
        return true;
    }
};

CameraCapture::CameraCapture(const CaptureSettings& settings) : CameraCapture(settings, capture::libv4l2Device()) {}

CameraCapture::CameraCapture(const CaptureSettings& settings, std::shared_ptr<capture::VideoDevice> device)
    : impl_(std::make_unique<Impl>(std::move(device))) {
    impl_->open(settings);
}
CameraCapture::~CameraCapture() = default;
CameraCapture::CameraCapture(CameraCapture&&) noexcept = default;
CameraCapture& CameraCapture::operator=(CameraCapture&&) noexcept = default;

CaptureStatus CameraCapture::read(CapturedFrame& frame) { return impl_->read(frame); }
const std::string& CameraCapture::device() const { return impl_->device; }
int CameraCapture::width() const { return impl_->width; }
int CameraCapture::height() const { return impl_->height; }
double CameraCapture::fps() const { return impl_->fps; }
CaptureFormat CameraCapture::format() const { return impl_->format; }

std::string CameraCapture::description() const {
    char rate[32];
    std::snprintf(rate, sizeof rate, "%.0f", impl_->fps);
    return impl_->card + " (" + impl_->device + "): " + (impl_->format == CaptureFormat::Mjpeg ? "MJPEG " : "YUYV ") +
           std::to_string(impl_->width) + "x" + std::to_string(impl_->height) + " at " + rate + " fps";
}

}  // namespace facetrack
