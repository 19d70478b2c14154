#include "core/image.hpp"

#include "facetrack/error.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <string>

namespace facetrack {

int bytesPerPixel(PixelFormat format) {
    switch (format) {
        case PixelFormat::Gray8: return 1;
        case PixelFormat::Bgr8:
        case PixelFormat::Rgb8: return 3;
        case PixelFormat::Bgra8:
        case PixelFormat::Rgba8: return 4;
    }
    throw Error("unknown pixel format " + std::to_string(static_cast<int>(format)));
}

namespace core {

cv::Mat wrap(const ImageView& view) {
    const int bpp = bytesPerPixel(view.format);
    if (view.data == nullptr) throw Error("invalid image: null pixel pointer");
    if (view.width <= 0 || view.height <= 0) {
        throw Error("invalid image: size " + std::to_string(view.width) + "x" + std::to_string(view.height));
    }
    if (view.width > std::numeric_limits<int>::max() / bpp ||
        view.stride < static_cast<std::size_t>(view.width) * static_cast<std::size_t>(bpp)) {
        throw Error("invalid image: stride " + std::to_string(view.stride) + " bytes is shorter than a row of " +
                    std::to_string(view.width) + " pixels x " + std::to_string(bpp) + " bytes");
    }
    return cv::Mat(view.height, view.width, CV_8UC(bpp), const_cast<std::uint8_t*>(view.data), view.stride);
}

cv::Mat toBgr(const ImageView& view) {
    const cv::Mat src = wrap(view);
    cv::Mat bgr;
    switch (view.format) {
        case PixelFormat::Bgr8: return src;
        case PixelFormat::Gray8: cv::cvtColor(src, bgr, cv::COLOR_GRAY2BGR); break;
        case PixelFormat::Rgb8: cv::cvtColor(src, bgr, cv::COLOR_RGB2BGR); break;
        case PixelFormat::Bgra8: cv::cvtColor(src, bgr, cv::COLOR_BGRA2BGR); break;
        case PixelFormat::Rgba8: cv::cvtColor(src, bgr, cv::COLOR_RGBA2BGR); break;
    }
    return bgr;
}

cv::Mat toGray(const ImageView& view, cv::Mat& gray) {
    const cv::Mat src = wrap(view);
    switch (view.format) {
        case PixelFormat::Gray8: return src;
        case PixelFormat::Bgr8: cv::cvtColor(src, gray, cv::COLOR_BGR2GRAY); break;
        case PixelFormat::Rgb8: cv::cvtColor(src, gray, cv::COLOR_RGB2GRAY); break;
        case PixelFormat::Bgra8: cv::cvtColor(src, gray, cv::COLOR_BGRA2GRAY); break;
        case PixelFormat::Rgba8: cv::cvtColor(src, gray, cv::COLOR_RGBA2GRAY); break;
    }
    return gray;
}

ImageView viewOf(const cv::Mat& mat) {
    if (mat.depth() != CV_8U || (mat.channels() != 1 && mat.channels() != 3)) {
        throw Error("viewOf: expected an 8-bit grey or BGR image");
    }
    return ImageView{mat.data, mat.cols, mat.rows, mat.step[0],
                     mat.channels() == 1 ? PixelFormat::Gray8 : PixelFormat::Bgr8};
}

void warpAffineGray(const cv::Mat& gray, const cv::Matx23d& a, cv::Size size, cv::Mat& patch) {
    if (gray.empty() || gray.type() != CV_8UC1) throw Error("warpAffineGray: the frame must be 8-bit grey and not empty");
    if (size.width <= 0 || size.height <= 0) throw Error("warpAffineGray: the patch must have a positive size");
    patch.create(size, CV_8UC1);
    // OpenCV's fixed point (imgproc/src/imgwarp.cpp): the map in 1/1024 px, each sample point rounded
    // to 1/32 px. Its 32-bit sums wrap where they overflow; so do these (unsigned, without undefined behaviour).
    constexpr int kMapBits = 10, kFractionBits = 5, kFractions = 1 << kFractionBits;
    constexpr double kMapScale = 1 << kMapBits;
    constexpr unsigned kRound = (1u << kMapBits) / kFractions / 2;
    const unsigned lastColumn = static_cast<unsigned>(std::max(gray.cols - 1, 0));
    const unsigned lastRow = static_cast<unsigned>(std::max(gray.rows - 1, 0));
    const std::uint8_t* pixels = gray.data;
    const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(gray.step[0]);
    // Up to kChunk columns at a time: each column's step from the row's start, as OpenCV computes it,
    // then each pixel's sample point in 32nds of a pixel.
    constexpr int kChunk = 256;
    std::array<unsigned, kChunk> columnX, columnY;
    std::array<int, kChunk> pointX, pointY;
    for (int first = 0; first < size.width; first += kChunk) {
        const int columns = std::min(kChunk, size.width - first);
        for (int k = 0; k < columns; ++k) {
            columnX[static_cast<std::size_t>(k)] = static_cast<unsigned>(cv::saturate_cast<int>(a(0, 0) * (first + k) * kMapScale));
            columnY[static_cast<std::size_t>(k)] = static_cast<unsigned>(cv::saturate_cast<int>(a(1, 0) * (first + k) * kMapScale));
        }
        for (int v = 0; v < size.height; ++v) {
            const unsigned x0 = static_cast<unsigned>(cv::saturate_cast<int>((a(0, 1) * v + a(0, 2)) * kMapScale)) + kRound;
            const unsigned y0 = static_cast<unsigned>(cv::saturate_cast<int>((a(1, 1) * v + a(1, 2)) * kMapScale)) + kRound;
            for (int k = 0; k < columns; ++k) {
                const auto c = static_cast<std::size_t>(k);
                pointX[c] = static_cast<int>(x0 + columnX[c]) >> (kMapBits - kFractionBits);
                pointY[c] = static_cast<int>(y0 + columnY[c]) >> (kMapBits - kFractionBits);
            }
            std::uint8_t* out = patch.ptr<std::uint8_t>(v) + first;
            for (int k = 0; k < columns; ++k) {
                const int x = pointX[static_cast<std::size_t>(k)], y = pointY[static_cast<std::size_t>(k)];
                int c0 = cv::saturate_cast<short>(x >> kFractionBits), r0 = cv::saturate_cast<short>(y >> kFractionBits);
                const int fx = x & (kFractions - 1), fy = y & (kFractions - 1);
                int c1 = c0 + 1, r1 = r0 + 1;
                if (static_cast<unsigned>(c0) >= lastColumn || static_cast<unsigned>(r0) >= lastRow) {  // a neighbour outside
                    c0 = std::clamp(c0, 0, gray.cols - 1), c1 = std::clamp(c1, 0, gray.cols - 1);
                    r0 = std::clamp(r0, 0, gray.rows - 1), r1 = std::clamp(r1, 0, gray.rows - 1);
                }
                const std::uint8_t* top = pixels + static_cast<std::ptrdiff_t>(r0) * step;
                const std::uint8_t* bottom = pixels + static_cast<std::ptrdiff_t>(r1) * step;
                // (32 - fy) ((32 - fx) p00 + fx p01) + fy ((32 - fx) p10 + fx p11), with fewer products.
                const int upper = kFractions * top[c0] + fx * (top[c1] - top[c0]);
                const int lower = kFractions * bottom[c0] + fx * (bottom[c1] - bottom[c0]);
                out[k] = static_cast<std::uint8_t>((kFractions * upper + fy * (lower - upper) + 512) >> 10);
            }
        }
    }
}
}  // namespace core
}  // namespace facetrack
