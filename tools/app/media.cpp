#include "media.hpp"

#include "facetrack/error.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>

namespace fs = std::filesystem;

namespace facetrack::tools {

bool isImageFile(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    for (const char* known : {".jpg", ".jpeg", ".png", ".bmp", ".pgm", ".ppm", ".tif", ".tiff", ".webp"}) {
        if (ext == known) return true;
    }
    return false;
}

std::vector<std::string> listImages(const std::string& dir) {
    std::vector<std::string> images;
    for (const auto& entry : fs::recursive_directory_iterator(dir, fs::directory_options::skip_permission_denied)) {
        if (entry.is_regular_file() && isImageFile(entry.path().string())) images.push_back(entry.path().string());
    }
    std::sort(images.begin(), images.end());
    return images;
}

MediaReader MediaReader::open(const std::string& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw Error("no such file or directory: '" + path + "'");
    MediaReader reader;
    if (fs::is_directory(path, ec)) {
        reader.images_ = listImages(path);
        if (reader.images_.empty()) throw Error("no images (.jpg, .png, ...) in folder '" + path + "'");
    } else if (isImageFile(path)) {
        reader.images_ = {path};
        reader.single_image_ = true;
    } else {
        reader.video_.open(path, cv::CAP_FFMPEG);
        if (!reader.video_.isOpened()) throw Error("cannot read '" + path + "' as an image or a video");
        reader.video_name_ = path;
        reader.fps_ = reader.video_.get(cv::CAP_PROP_FPS);
        if (!(reader.fps_ > 0.0 && reader.fps_ < 1000.0)) reader.fps_ = 30.0;
    }
    return reader;
}

MediaReader MediaReader::openCamera(const CaptureSettings& settings) {
    MediaReader reader;
    reader.camera_.emplace(settings);
    reader.video_name_ = settings.device;
    reader.fps_ = reader.camera_->fps();
    return reader;
}

std::string MediaReader::describe() const {
    if (camera_) return camera_->description();
    if (video_.isOpened()) return video_name_;
    return images_.size() == 1 ? images_.front() : std::to_string(images_.size()) + " images";
}

bool MediaReader::next(MediaFrame& frame) {
    switch (read(frame)) {
        case ReadStatus::Frame:
            return true;
        case ReadStatus::End:
            return false;
        case ReadStatus::Timeout:
            throw Error("camera " + video_name_ + " sent no frame in time (is it in use, or covered?)");
        case ReadStatus::Disconnected:
            throw Error("camera " + video_name_ + " went away (unplugged?)");
    }
    return false;
}

ReadStatus MediaReader::read(MediaFrame& frame) {
    if (camera_) {
        const CaptureStatus status = camera_->read(captured_);
        if (status == CaptureStatus::Timeout) return ReadStatus::Timeout;
        if (status == CaptureStatus::Disconnected) return ReadStatus::Disconnected;
        frame.bgr = cv::Mat(captured_.height, captured_.width, CV_8UC3, captured_.bgr.data());
        frame.source = video_name_;
        frame.index = video_index_++;
        frame.time_s = captured_.timestamp_s;
        return ReadStatus::Frame;
    }
    if (video_.isOpened()) {
        if (!video_.read(frame.bgr) || frame.bgr.empty()) return ReadStatus::End;
        frame.source = video_name_;
        frame.index = video_index_++;
        frame.time_s = frame.index / fps_;
        return ReadStatus::Frame;
    }
    while (next_image_ < images_.size()) {
        const std::string& path = images_[next_image_++];
        frame.bgr = cv::imread(path, cv::IMREAD_COLOR);
        if (frame.bgr.empty()) {
            // The one image asked for is the whole input; in a folder, one bad file is reported and passed over.
            if (single_image_) throw Error("cannot read image '" + path + "' (not an image, or damaged)");
            std::cerr << "facetrack: skipping unreadable image '" << path << "'\n";
            ++unreadable_images_;
            continue;
        }
        frame.source = path;
        frame.index = static_cast<int>(next_image_ - 1);
        frame.time_s = frame.index;
        return ReadStatus::Frame;
    }
    if (!images_.empty() && unreadable_images_ == images_.size())
        throw Error("none of the " + std::to_string(images_.size()) + " images in the folder could be read");
    return ReadStatus::End;
}

std::vector<MediaFrame> readAllFrames(const std::string& path, int maxFrames, cv::Size size) {
    auto reader = MediaReader::open(path);
    std::vector<MediaFrame> frames;
    MediaFrame frame;
    while ((maxFrames < 0 || static_cast<int>(frames.size()) < maxFrames) && reader.next(frame)) {
        if (!size.empty()) {
            const double scale = std::min(static_cast<double>(size.width) / frame.bgr.cols,
                                          static_cast<double>(size.height) / frame.bgr.rows);
            cv::Mat scaled, boxed(size, CV_8UC3, cv::Scalar::all(0));
            cv::resize(frame.bgr, scaled, cv::Size(), scale, scale, scale < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
            scaled.copyTo(boxed(cv::Rect((size.width - scaled.cols) / 2, (size.height - scaled.rows) / 2, scaled.cols, scaled.rows)));
            frame.bgr = boxed;
        }
        frames.push_back(frame);
        frame = MediaFrame{};  // the reader may reuse buffers
    }
    if (frames.empty()) throw Error("no frames in '" + path + "'");
    return frames;
}

cv::Size parseSize(const std::string& text) {
    if (text.empty()) return {};
    int w = 0, h = 0;
    char x = 0, extra = 0;
    if (std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || x != 'x' || w < 16 || h < 16 || w > 8192 || h > 8192) {
        throw Error("a size is WIDTHxHEIGHT, e.g. 640x480 (16..8192), not '" + text + "'");
    }
    return {w, h};
}

}  // namespace facetrack::tools
