#pragma once
/// \file
/// A non-owning view of caller-owned pixels: the frame type going into
/// facetrack. facetrack never keeps a view past the call it was given to.

#include <cstddef>
#include <cstdint>

namespace facetrack {

enum class PixelFormat {
    Gray8,  ///< 1 byte per pixel
    Bgr8,   ///< 3 bytes per pixel, blue first (OpenCV's order)
    Rgb8,   ///< 3 bytes per pixel, red first
    Bgra8,  ///< 4 bytes per pixel, alpha ignored
    Rgba8,  ///< 4 bytes per pixel, alpha ignored
};

/// Bytes per pixel of a format.
int bytesPerPixel(PixelFormat format);

/// Rows of `width` pixels, `stride` bytes apart, starting at `data`. The view
/// does not own the pixels; they must outlive the call that reads them.
/// Functions taking an ImageView throw facetrack::Error when it is invalid
/// (null data, non-positive size, stride shorter than a row).
struct ImageView {
    const std::uint8_t* data = nullptr;
    int width = 0;
    int height = 0;
    std::size_t stride = 0;  ///< bytes from one row to the next
    PixelFormat format = PixelFormat::Bgr8;
};

}  // namespace facetrack
