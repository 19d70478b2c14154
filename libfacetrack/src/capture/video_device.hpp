#pragma once
// The device calls CameraCapture makes (internal): libv4l2 on a real camera,
// a scripted stand-in in the tests, so that negotiation, streaming, timeouts
// and unplugging are tested without a webcam.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

namespace facetrack::capture {

class VideoDevice {
public:
    virtual ~VideoDevice() = default;
    /// Opens a V4L2 node read-write, non-blocking: a descriptor, or -1 with
    /// errno set (ENOTTY: the node is not a V4L2 device).
    virtual int open(const std::string& path) = 0;
    virtual void close(int fd) = 0;
    /// ioctl(2); -1 with errno set on failure.
    virtual int ioctl(int fd, unsigned long request, void* arg) = 0;
    /// Maps a streaming buffer (MAP_SHARED, read-write); MAP_FAILED on failure.
    virtual void* mmap(std::size_t length, int fd, std::int64_t offset) = 0;
    virtual void munmap(void* start, std::size_t length) = 0;
    /// poll(2) on one descriptor for input: > 0 ready (see revents), 0 timed
    /// out, -1 with errno set.
    virtual int poll(int fd, int timeout_ms, short& revents) = 0;
};

/// The real thing: libv4l2 with its format conversion off (we convert).
std::shared_ptr<VideoDevice> libv4l2Device();

}  // namespace facetrack::capture
