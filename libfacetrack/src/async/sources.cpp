// The FrameSources of async_tracker.hpp: a webcam (CameraCapture), a clip
// (OpenCV's VideoCapture) and images (one file or a folder).

#include "facetrack/async_tracker.hpp"

#include "core/image.hpp"
#include "facetrack/error.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <filesystem>
#include <optional>

namespace facetrack {

namespace {

class CameraSource final : public FrameSource {
public:
    explicit CameraSource(const CaptureSettings& settings) : camera_(settings) {}
    Status read(ImageView& frame, double& time_s) override {
        switch (camera_.read(frame_)) {
            case CaptureStatus::Frame:
                frame = frame_.view();
                time_s = frame_.timestamp_s;
                return Status::Frame;
            case CaptureStatus::Timeout:
                return Status::Timeout;
            case CaptureStatus::Disconnected:
                return Status::Disconnected;
        }
        return Status::Disconnected;
    }
    bool live() const override { return true; }
    bool separateScenes() const override { return false; }
    std::string describe() const override { return camera_.description(); }

private:
    CameraCapture camera_;
    CapturedFrame frame_;
};

bool isImage(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext == ".jpg" || ext == ".jpeg" || ext == ".png" || ext == ".bmp" || ext == ".ppm" || ext == ".pgm";
}

class MediaSource final : public FrameSource {
public:
    explicit MediaSource(const std::string& path) : path_(path) {
        namespace fs = std::filesystem;
        std::error_code ec;
        if (!fs::exists(path, ec)) throw Error("'" + path + "' does not exist");
        if (fs::is_directory(path, ec)) {
            for (const auto& entry : fs::recursive_directory_iterator(path, ec)) {
                if (entry.is_regular_file(ec) && isImage(entry.path())) images_.push_back(entry.path().string());
            }
            std::sort(images_.begin(), images_.end());
            if (images_.empty()) throw Error("'" + path + "' holds no images");
        } else if (isImage(path)) {
            images_.push_back(path);
        } else {
            video_.open(path);
            if (!video_.isOpened()) throw Error("'" + path + "' is neither an image, a folder of images nor a readable video");
            fps_ = video_.get(cv::CAP_PROP_FPS);
            if (!(fps_ > 0.0 && fps_ < 1000.0)) fps_ = 30.0;
        }
    }

    Status read(ImageView& frame, double& time_s) override {
        if (video_.isOpened()) {
            if (!video_.read(bgr_) || bgr_.empty()) return Status::End;
            time_s = index_++ / fps_;
        } else {
            // Unreadable images are skipped: a folder of photos goes on.
            do {
                if (next_image_ >= images_.size()) return Status::End;
                bgr_ = cv::imread(images_[next_image_++], cv::IMREAD_COLOR);
            } while (bgr_.empty());
            time_s = static_cast<double>(index_++);  // photos: 1 s apart
        }
        frame = core::viewOf(bgr_);
        return Status::Frame;
    }
    bool live() const override { return false; }
    bool separateScenes() const override { return !video_.isOpened(); }
    std::string describe() const override { return path_; }

private:
    std::string path_;
    cv::VideoCapture video_;
    double fps_ = 30.0;
    std::vector<std::string> images_;
    std::size_t next_image_ = 0;
    long index_ = 0;
    cv::Mat bgr_;
};

}  // namespace

std::unique_ptr<FrameSource> openCameraSource(const CaptureSettings& settings) { return std::make_unique<CameraSource>(settings); }
std::unique_ptr<FrameSource> openMediaSource(const std::string& path) { return std::make_unique<MediaSource>(path); }

}  // namespace facetrack
