#pragma once
// The CLI's inputs: one image, a folder of images (sorted, recursive), a video
// clip, or a camera, read frame by frame as BGR.

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include <string>
#include <vector>

namespace facetrack::cli {

struct MediaFrame {
    std::string source;  ///< the image's path, or the clip's / camera's
    int index = 0;       ///< frame number within the source, from 0
    double time_s = 0.0; ///< timestamp: index / fps for clips, 0 for images
    cv::Mat bgr;
};

class MediaReader {
public:
    /// Throws facetrack::Error with a clear message when the path does not
    /// exist or is neither an image, a folder of images nor a readable video.
    static MediaReader open(const std::string& path);
    static MediaReader openCamera(const std::string& device);

    /// False at the end. Unreadable images in a folder are reported on stderr and skipped.
    bool next(MediaFrame& frame);
    bool isVideo() const { return video_.isOpened(); }
    double fps() const { return fps_; }

private:
    std::vector<std::string> images_;
    std::size_t next_image_ = 0;
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

/// /dev/video* devices, sorted.
std::vector<std::string> listCameras();

}  // namespace facetrack::cli
