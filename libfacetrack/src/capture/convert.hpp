#pragma once
// Camera pixel formats to BGR (internal; CameraCapture uses them and the tests
// call them on buffers they build).

#include <opencv2/core.hpp>

#include <cstddef>
#include <cstdint>

namespace facetrack::capture {

/// YUYV (YUV 4:2:2: Y0 U Y1 V per pixel pair, BT.601 video range as webcams
/// send it) to BGR. `stride` is the bytes per row (>= 2 * width); width must
/// be even. Throws Error when the buffer is smaller than stride * height.
void yuyvToBgr(const std::uint8_t* yuyv, std::size_t size, int width, int height, std::size_t stride, cv::Mat& bgr);

/// Decodes one MJPEG frame (a JPEG, possibly without Huffman tables, as many
/// webcams send them) into `bgr`, reusing its buffer when the size matches.
/// False when the data is not a whole, decodable JPEG of width x height pixels.
bool decodeMjpeg(const std::uint8_t* data, std::size_t size, int width, int height, cv::Mat& bgr);

}  // namespace facetrack::capture
