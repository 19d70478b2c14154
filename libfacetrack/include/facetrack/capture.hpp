#pragma once
/// \file
/// Webcam capture on Linux (V4L2 through libv4l2): open a /dev/videoN device,
/// negotiate YUYV or MJPEG at a requested size and rate, stream through
/// memory-mapped buffers and hand out BGR frames ready for Tracker::process.
///
/// Ownership and threads: a CameraCapture owns its device and its frame
/// buffers and is used by one thread at a time; CapturedFrame owns its pixels.
/// Optional at build time (FACETRACK_WITH_V4L2): without it, opening throws.
///
///     facetrack::CameraCapture camera({"/dev/video0", 640, 480, 30.0});
///     facetrack::CapturedFrame frame;
///     facetrack::FrameResult result;  // reused frame to frame
///     while (camera.read(frame) != facetrack::CaptureStatus::Disconnected) {
///         if (frame.width > 0) tracker.process(frame.view(), frame.timestamp_s, result);
///     }
///
/// Opening fails with a facetrack::Error that says what to do: which
/// /dev/video* exist when the device does not, who to ask when it is busy or
/// not permitted, which formats it offers when none is YUYV or MJPEG.

#include "facetrack/image.hpp"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace facetrack {

namespace capture {
class VideoDevice;
}

enum class CaptureFormat {
    Auto,   ///< YUYV up to 640x480 (no decoding cost), MJPEG above (USB bandwidth); whichever the device has
    Yuyv,   ///< YUV 4:2:2, two bytes per pixel
    Mjpeg,  ///< a JPEG per frame
};

/// "yuyv", "mjpeg", "auto".
std::string toString(CaptureFormat format);

struct CaptureSettings {
    std::string device = "/dev/video0";
    int width = 640;  ///< requested; the driver may pick the nearest size it has
    int height = 480;
    double fps = 30.0;  ///< requested; not every driver honours it
    CaptureFormat format = CaptureFormat::Auto;
    int timeout_ms = 2000;  ///< read() gives up waiting for a frame after this long
};

/// A frame in BGR, owned. read() reuses the buffer: no allocation per frame
/// once the size is known.
struct CapturedFrame {
    std::vector<std::uint8_t> bgr;
    int width = 0;
    int height = 0;
    double timestamp_s = 0.0;    ///< steady clock, from when the camera was opened
    std::uint64_t sequence = 0;  ///< frames delivered so far, from 1

    ImageView view() const { return {bgr.data(), width, height, static_cast<std::size_t>(width) * 3, PixelFormat::Bgr8}; }
};

enum class CaptureStatus {
    Frame,         ///< `frame` holds a new image
    Timeout,       ///< no frame within timeout_ms; the device is still there
    Disconnected,  ///< the device went away (unplugged); reopen it to continue
};

class CameraCapture {
public:
    /// Opens and starts streaming. Throws Error with a message a user can act on.
    explicit CameraCapture(const CaptureSettings& settings);
    /// The same through other device calls than libv4l2's (facetrack's tests
    /// stand in for a camera this way).
    CameraCapture(const CaptureSettings& settings, std::shared_ptr<capture::VideoDevice> device);
    ~CameraCapture();
    CameraCapture(CameraCapture&&) noexcept;
    CameraCapture& operator=(CameraCapture&&) noexcept;
    CameraCapture(const CameraCapture&) = delete;
    CameraCapture& operator=(const CameraCapture&) = delete;

    /// Waits for the next frame (at most timeout_ms). Frames that fail to
    /// decode (a corrupt JPEG now and then is normal for webcams) are dropped
    /// and the wait goes on. Never blocks past the timeout.
    CaptureStatus read(CapturedFrame& frame);

    const std::string& device() const;
    /// The negotiated mode, which may differ from the one requested.
    int width() const;
    int height() const;
    double fps() const;
    CaptureFormat format() const;
    /// e.g. "HD Webcam C270 (/dev/video0): MJPEG 640x480 at 30 fps".
    std::string description() const;

    /// The /dev/video* nodes that exist, sorted. Not all are cameras: a
    /// webcam often has a second node for metadata.
    static std::vector<std::string> listDevices();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace facetrack
