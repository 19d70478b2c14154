#pragma once
// The CLI's inputs: one image, a folder of images (sorted, recursive), a video
// clip, or a camera (CameraCapture), read frame by frame as BGR.

#include "facetrack/capture.hpp"

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include <optional>
#include <string>
#include <vector>

namespace facetrack::tools {

struct MediaFrame {
    std::string source;   ///< the image's path, or the clip's / camera's
    int index = 0;        ///< frame (or image) number within the source, from 0
    double time_s = 0.0;  ///< timestamp: index / fps for clips, index (1 s apart) for images
    cv::Mat bgr;
};

enum class ReadStatus { Frame, End, Timeout, Disconnected };

class MediaReader {
public:
    /// Throws facetrack::Error with a clear message when the path does not
    /// exist or is neither an image, a folder of images nor a readable video.
    static MediaReader open(const std::string& path);
    /// A V4L2 camera (CameraCapture); throws its Error when it cannot be opened.
    static MediaReader openCamera(const CaptureSettings& settings);

    /// The next frame. A camera's frame is a view of the reader's buffer,
    /// valid until the next call; clone it to keep it. Unreadable images in a
    /// folder are reported on stderr and skipped; a single image that cannot
    /// be read, or a folder none of whose images can, throws Error. Timeout
    /// and Disconnected come from cameras only.
    ReadStatus read(MediaFrame& frame);
    /// read(), with a camera's timeout or disconnection thrown as Error: false at the end.
    bool next(MediaFrame& frame);

    bool isVideo() const { return video_.isOpened(); }
    /// An image or a folder of images: each is its own scene (Tracker::reset
    /// between them), and they are timed 1 s apart, a slideshow.
    bool isStillImages() const { return !video_.isOpened() && !camera_; }
    bool isCamera() const { return camera_.has_value(); }
    double fps() const { return fps_; }
    /// The path, or the camera's description.
    std::string describe() const;

private:
    std::optional<CameraCapture> camera_;
    CapturedFrame captured_;
    std::vector<std::string> images_;
    std::size_t next_image_ = 0;
    std::size_t unreadable_images_ = 0;
    bool single_image_ = false;  ///< one image named, not a folder
    cv::VideoCapture video_;
    std::string video_name_;
    double fps_ = 0.0;
    int video_index_ = 0;
};

bool isImageFile(const std::string& path);

/// Every image file below dir, sorted by path.
std::vector<std::string> listImages(const std::string& dir);

/// Every frame of `path` (at most maxFrames when >= 0), decoded up front so
/// that timing loops do not time the decoder. A non-empty `size` letterboxes
/// each frame into that size (scaled to fit, black borders).
std::vector<MediaFrame> readAllFrames(const std::string& path, int maxFrames, cv::Size size = {});

/// "640x480" -> cv::Size; "" -> empty size. Throws Error on anything else.
cv::Size parseSize(const std::string& text);

}  // namespace facetrack::tools
