#include "core/image.hpp"

#include "facetrack/error.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <string>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace facetrack {

int bytesPerPixel(PixelFormat format) {
    switch (format) {
        case PixelFormat::Gray8:
            return 1;
        case PixelFormat::Bgr8:
        case PixelFormat::Rgb8:
            return 3;
        case PixelFormat::Bgra8:
        case PixelFormat::Rgba8:
            return 4;
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
        case PixelFormat::Bgr8:
            return src;
        case PixelFormat::Gray8:
            cv::cvtColor(src, bgr, cv::COLOR_GRAY2BGR);
            break;
        case PixelFormat::Rgb8:
            cv::cvtColor(src, bgr, cv::COLOR_RGB2BGR);
            break;
        case PixelFormat::Bgra8:
            cv::cvtColor(src, bgr, cv::COLOR_BGRA2BGR);
            break;
        case PixelFormat::Rgba8:
            cv::cvtColor(src, bgr, cv::COLOR_RGBA2BGR);
            break;
    }
    return bgr;
}

cv::Mat toGray(const ImageView& view, cv::Mat& gray) {
    const cv::Mat src = wrap(view);
    if (view.format == PixelFormat::Gray8) return src;
    // A buffer that holds an earlier grey frame's header views the caller's pixels (a Mat
    // reuses data of the same size): converting into it would write into them.
    if (gray.data && !gray.u) gray.release();
    switch (view.format) {
        case PixelFormat::Gray8:
            break;
        case PixelFormat::Bgr8:
            cv::cvtColor(src, gray, cv::COLOR_BGR2GRAY);
            break;
        case PixelFormat::Rgb8:
            cv::cvtColor(src, gray, cv::COLOR_RGB2GRAY);
            break;
        case PixelFormat::Bgra8:
            cv::cvtColor(src, gray, cv::COLOR_BGRA2GRAY);
            break;
        case PixelFormat::Rgba8:
            cv::cvtColor(src, gray, cv::COLOR_RGBA2GRAY);
            break;
    }
    return gray;
}

ImageView viewOf(const cv::Mat& mat) {
    if (mat.depth() != CV_8U || (mat.channels() != 1 && mat.channels() != 3)) {
        throw Error("viewOf: expected an 8-bit grey or BGR image");
    }
    return ImageView{mat.data, mat.cols, mat.rows, mat.step[0], mat.channels() == 1 ? PixelFormat::Gray8 : PixelFormat::Bgr8};
}

namespace {

/// OpenCV's fixed point for warpAffine (imgproc/src/imgwarp.cpp): the map in 1/1024 px, each
/// sample point rounded to 1/32 px.
constexpr int kMapBits = 10, kFractionBits = 5, kFractions = 1 << kFractionBits;

/// The bilinear blend of one sample point in 32nds of a pixel: (32 - fy) ((32 - fx) p00 + fx p01)
/// + fy ((32 - fx) p10 + fx p11), rounded, with fewer products.
inline std::uint8_t blend(int p00, int p01, int p10, int p11, int fx, int fy) {
    const int upper = kFractions * p00 + fx * (p01 - p00);
    const int lower = kFractions * p10 + fx * (p11 - p10);
    return static_cast<std::uint8_t>((kFractions * upper + fy * (lower - upper) + 512) >> 10);
}

#if defined(__x86_64__)
/// Eight sample points at a time where all eight and their right neighbours' dword lie inside
/// the frame (column <= cols - 4, row <= rows - 2): two gathers of four bytes each give a
/// point's four pixels, and the blend is blend()'s, in 32-bit lanes. Returns how many leading
/// points it wrote (a multiple of 8); the caller does the rest point by point. The gathers
/// make the cut 0.4x as long as one pixel at a time (BM_PatchCut).
__attribute__((target("avx2"))) int blendRowAvx2(const std::uint8_t* pixels, std::ptrdiff_t step, int cols, int rows, const int* pointX,
                                                 const int* pointY, int count, std::uint8_t* out) {
    const __m256i lastSafeColumn = _mm256_set1_epi32(cols - 4), lastSafeRow = _mm256_set1_epi32(rows - 2);
    const __m256i zero = _mm256_setzero_si256(), fractionMask = _mm256_set1_epi32(kFractions - 1);
    const __m256i byteMask = _mm256_set1_epi32(0xff), rowStep = _mm256_set1_epi32(static_cast<int>(step));
    const __m256i half = _mm256_set1_epi32(512);
    int k = 0;
    for (; k + 8 <= count; k += 8) {
        const __m256i x = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(pointX + k));
        const __m256i y = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(pointY + k));
        const __m256i column = _mm256_srai_epi32(x, kFractionBits), row = _mm256_srai_epi32(y, kFractionBits);
        const __m256i columnOutside = _mm256_or_si256(_mm256_cmpgt_epi32(zero, column), _mm256_cmpgt_epi32(column, lastSafeColumn));
        const __m256i rowOutside = _mm256_or_si256(_mm256_cmpgt_epi32(zero, row), _mm256_cmpgt_epi32(row, lastSafeRow));
        const __m256i outside = _mm256_or_si256(columnOutside, rowOutside);
        if (!_mm256_testz_si256(outside, outside)) break;
        const __m256i offset = _mm256_add_epi32(_mm256_mullo_epi32(row, rowStep), column);
        const __m256i top = _mm256_i32gather_epi32(reinterpret_cast<const int*>(pixels), offset, 1);
        const __m256i bottom = _mm256_i32gather_epi32(reinterpret_cast<const int*>(pixels), _mm256_add_epi32(offset, rowStep), 1);
        const __m256i p00 = _mm256_and_si256(top, byteMask), p01 = _mm256_and_si256(_mm256_srli_epi32(top, 8), byteMask);
        const __m256i p10 = _mm256_and_si256(bottom, byteMask), p11 = _mm256_and_si256(_mm256_srli_epi32(bottom, 8), byteMask);
        const __m256i fx = _mm256_and_si256(x, fractionMask), fy = _mm256_and_si256(y, fractionMask);
        const __m256i upper = _mm256_add_epi32(_mm256_slli_epi32(p00, kFractionBits), _mm256_mullo_epi32(fx, _mm256_sub_epi32(p01, p00)));
        const __m256i lower = _mm256_add_epi32(_mm256_slli_epi32(p10, kFractionBits), _mm256_mullo_epi32(fx, _mm256_sub_epi32(p11, p10)));
        const __m256i vertical = _mm256_mullo_epi32(fy, _mm256_sub_epi32(lower, upper));
        const __m256i sum = _mm256_add_epi32(_mm256_slli_epi32(upper, kFractionBits), vertical);
        const __m256i blended = _mm256_srai_epi32(_mm256_add_epi32(sum, half), 2 * kFractionBits);
        const __m128i words = _mm_packus_epi32(_mm256_castsi256_si128(blended), _mm256_extracti128_si256(blended, 1));
        _mm_storel_epi64(reinterpret_cast<__m128i*>(out + k), _mm_packus_epi16(words, words));
    }
    return k;
}
#endif

}  // namespace

bool gathersFit(const cv::Mat& gray) {
#if defined(__x86_64__)
    static const bool avx2 = __builtin_cpu_supports("avx2");
    return avx2 && static_cast<double>(gray.step[0]) * gray.rows < static_cast<double>(std::numeric_limits<int>::max());
#else
    (void)gray;
    return false;
#endif
}

void warpAffineGray(const cv::Mat& gray, const cv::Matx23d& a, cv::Size size, cv::Mat& patch) {
    if (gray.empty() || gray.type() != CV_8UC1) throw Error("warpAffineGray: the frame must be 8-bit grey and not empty");
    if (size.width <= 0 || size.height <= 0) throw Error("warpAffineGray: the patch must have a positive size");
    patch.create(size, CV_8UC1);
    // OpenCV's 32-bit sums wrap where they overflow; so do these (unsigned, without undefined behaviour).
    constexpr double kMapScale = 1 << kMapBits;
    constexpr unsigned kRound = (1u << kMapBits) / kFractions / 2;
    const unsigned lastColumn = static_cast<unsigned>(std::max(gray.cols - 1, 0));
    const unsigned lastRow = static_cast<unsigned>(std::max(gray.rows - 1, 0));
    const std::uint8_t* pixels = gray.data;
    const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(gray.step[0]);
    // A column within a short needs no saturate_cast.
    const bool gather = gathersFit(gray) && gray.rows >= 2 && gray.cols >= 4 && gray.cols < std::numeric_limits<short>::max();
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
            const auto blendPoint = [&](int k) {
                const int x = pointX[static_cast<std::size_t>(k)], y = pointY[static_cast<std::size_t>(k)];
                int c0 = cv::saturate_cast<short>(x >> kFractionBits), r0 = cv::saturate_cast<short>(y >> kFractionBits);
                int c1 = c0 + 1, r1 = r0 + 1;
                if (static_cast<unsigned>(c0) >= lastColumn || static_cast<unsigned>(r0) >= lastRow) {  // a neighbour outside
                    c0 = std::clamp(c0, 0, gray.cols - 1), c1 = std::clamp(c1, 0, gray.cols - 1);
                    r0 = std::clamp(r0, 0, gray.rows - 1), r1 = std::clamp(r1, 0, gray.rows - 1);
                }
                const std::uint8_t* top = pixels + static_cast<std::ptrdiff_t>(r0) * step;
                const std::uint8_t* bottom = pixels + static_cast<std::ptrdiff_t>(r1) * step;
                out[k] = blend(top[c0], top[c1], bottom[c0], bottom[c1], x & (kFractions - 1), y & (kFractions - 1));
            };
            int k = 0;
#if defined(__x86_64__)
            // Runs of eight by the gathers; a run with a point near the border point by point.
            while (gather && columns - k >= 8) {
                k += blendRowAvx2(pixels, step, gray.cols, gray.rows, pointX.data() + k, pointY.data() + k, columns - k, out + k);
                if (columns - k < 8) break;
                for (const int end = k + 8; k < end; ++k) blendPoint(k);
            }
#endif
            for (; k < columns; ++k) blendPoint(k);
        }
    }
}
}  // namespace core
}  // namespace facetrack
