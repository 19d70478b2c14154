// The real device calls of CameraCapture: libv4l2 with its format
// conversion off (we convert), compiled when FACETRACK_WITH_V4L2 is on.

#include "capture/video_device.hpp"

#include <libv4l2.h>
#include <linux/videodev2.h>

#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>

namespace facetrack::capture {

namespace {

class Libv4l2Device final : public VideoDevice {
public:
    int open(const std::string& path) override {
        const int raw = ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
        if (raw < 0) return -1;
        // Asked before libv4l2 wraps the descriptor: it would print its own
        // complaint about a node that is not V4L2.
        v4l2_capability cap{};
        int queried;
        do {
            queried = ::ioctl(raw, VIDIOC_QUERYCAP, &cap);
        } while (queried == -1 && errno == EINTR);
        if (queried != 0) {
            ::close(raw);
            errno = ENOTTY;
            return -1;
        }
        const int fd = v4l2_fd_open(raw, V4L2_DISABLE_CONVERSION);
        if (fd < 0) {
            const int error = errno;
            ::close(raw);
            errno = error;
        }
        return fd;
    }
    void close(int fd) override { v4l2_close(fd); }
    int ioctl(int fd, unsigned long request, void* arg) override { return v4l2_ioctl(fd, request, arg); }
    void* mmap(std::size_t length, int fd, std::int64_t offset) override {
        return v4l2_mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, offset);
    }
    void munmap(void* start, std::size_t length) override { v4l2_munmap(start, length); }
    int poll(int fd, int timeout_ms, short& revents) override {
        pollfd p{fd, POLLIN, 0};
        const int ready = ::poll(&p, 1, timeout_ms);
        revents = p.revents;
        return ready;
    }
};

}  // namespace

std::shared_ptr<VideoDevice> libv4l2Device() { return std::make_shared<Libv4l2Device>(); }

}  // namespace facetrack::capture
