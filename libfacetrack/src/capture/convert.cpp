#include "capture/convert.hpp"

#include "facetrack/capture.hpp"
#include "facetrack/error.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>

namespace facetrack::capture {

void yuyvToBgr(const std::uint8_t* yuyv, std::size_t size, int width, int height, std::size_t stride, cv::Mat& bgr) {
    if (!yuyv || width <= 0 || height <= 0 || width % 2 != 0 || stride < static_cast<std::size_t>(width) * 2) {
        throw Error("YUYV frame: bad geometry " + std::to_string(width) + "x" + std::to_string(height) + ", stride " +
                    std::to_string(stride));
    }
    // The last row only needs its pixels, not a whole stride.
    const std::size_t needed = stride * static_cast<std::size_t>(height - 1) + static_cast<std::size_t>(width) * 2;
    if (size < needed) {
        throw Error("YUYV frame: " + std::to_string(size) + " bytes, " + std::to_string(needed) + " needed for " + std::to_string(width) +
                    "x" + std::to_string(height));
    }
    const cv::Mat packed(height, width, CV_8UC2, const_cast<std::uint8_t*>(yuyv), stride);
    cv::cvtColor(packed, bgr, cv::COLOR_YUV2BGR_YUYV);
}

bool decodeMjpeg(const std::uint8_t* data, std::size_t size, int width, int height, cv::Mat& bgr) {
    // A JPEG starts with SOI (FF D8); anything else is a torn or empty buffer.
    if (!data || size < 4 || data[0] != 0xFF || data[1] != 0xD8) return false;
    // A torn frame lacks its EOI (FF D9); libjpeg would pad it with grey and
    // call it a success. Some cameras pad after the EOI, hence the search.
    const std::size_t tail = size - std::min<std::size_t>(size, 1024);
    bool complete = false;
    for (std::size_t i = size - 1; i > tail && !complete; --i) complete = data[i - 1] == 0xFF && data[i] == 0xD9;
    if (!complete) return false;
    const cv::Mat encoded(1, static_cast<int>(size), CV_8UC1, const_cast<std::uint8_t*>(data));
    try {
        cv::imdecode(encoded, cv::IMREAD_COLOR, &bgr);
    } catch (const cv::Exception&) {
        return false;
    }
    return !bgr.empty() && bgr.cols == width && bgr.rows == height;
}

}  // namespace facetrack::capture

namespace facetrack {

std::string toString(CaptureFormat format) {
    switch (format) {
        case CaptureFormat::Auto:
            return "auto";
        case CaptureFormat::Yuyv:
            return "yuyv";
        case CaptureFormat::Mjpeg:
            return "mjpeg";
    }
    return "?";
}

}  // namespace facetrack
