#include "gaze/eye_patch.hpp"

#include "core/image.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace facetrack::gaze {

namespace {

#if defined(__x86_64__)
/// One patch row of a patch inside the frame, eight samples at a time: the portable loop's
/// sample points and blend, operation for operation (the same floats), each point's four
/// pixels from two gathered dwords. `inside` guarantees x0 + 3 and y0 + 1 are in the frame.
__attribute__((target("avx2"))) void sampleRowAvx2(const cv::Mat& gray, const cv::Matx23f& m, int y, float* row) {
    static_assert(kPatchWidth % 8 == 0, "a row is cut eight samples at a time");
    const __m256 one = _mm256_set1_ps(1.f), yf = _mm256_set1_ps(static_cast<float>(y));
    const __m256i byteMask = _mm256_set1_epi32(0xff), step = _mm256_set1_epi32(static_cast<int>(gray.step[0]));
    const int* pixels = reinterpret_cast<const int*>(gray.data);
    for (int x = 0; x < kPatchWidth; x += 8) {
        const __m256 xf = _mm256_add_ps(_mm256_set1_ps(static_cast<float>(x)), _mm256_setr_ps(0, 1, 2, 3, 4, 5, 6, 7));
        // (a00 x + a01 y) + a02, as the scalar loop rounds it.
        const __m256 sx = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(m(0, 0)), xf), _mm256_mul_ps(_mm256_set1_ps(m(0, 1)), yf)), _mm256_set1_ps(m(0, 2)));
        const __m256 sy = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(m(1, 0)), xf), _mm256_mul_ps(_mm256_set1_ps(m(1, 1)), yf)), _mm256_set1_ps(m(1, 2)));
        const __m256i x0 = _mm256_cvttps_epi32(sx), y0 = _mm256_cvttps_epi32(sy);
        const __m256 ax = _mm256_sub_ps(sx, _mm256_cvtepi32_ps(x0)), ay = _mm256_sub_ps(sy, _mm256_cvtepi32_ps(y0));
        const __m256i offset = _mm256_add_epi32(_mm256_mullo_epi32(y0, step), x0);
        const __m256i top = _mm256_i32gather_epi32(pixels, offset, 1);
        const __m256i bottom = _mm256_i32gather_epi32(pixels, _mm256_add_epi32(offset, step), 1);
        const __m256 p00 = _mm256_cvtepi32_ps(_mm256_and_si256(top, byteMask));
        const __m256 p01 = _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(top, 8), byteMask));
        const __m256 p10 = _mm256_cvtepi32_ps(_mm256_and_si256(bottom, byteMask));
        const __m256 p11 = _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(bottom, 8), byteMask));
        const __m256 bx = _mm256_sub_ps(one, ax);
        const __m256 upper = _mm256_add_ps(_mm256_mul_ps(bx, p00), _mm256_mul_ps(ax, p01));
        const __m256 lower = _mm256_add_ps(_mm256_mul_ps(bx, p10), _mm256_mul_ps(ax, p11));
        _mm256_storeu_ps(row + x, _mm256_add_ps(_mm256_mul_ps(_mm256_sub_ps(one, ay), upper), _mm256_mul_ps(ay, lower)));
    }
}
#endif

}  // namespace

int outerCorner(Eye eye) { return eye == Eye::Left ? 45 : 36; }
int innerCorner(Eye eye) { return eye == Eye::Left ? 42 : 39; }

bool cutEyePatch(const cv::Mat& gray, const Landmarks68& landmarks, Eye eye, EyePatch& out) {
    return cutEyePatch(gray, landmarks[static_cast<std::size_t>(outerCorner(eye))], landmarks[static_cast<std::size_t>(innerCorner(eye))],
                       eye == Eye::Left, out);
}

bool cutEyePatch(const cv::Mat& gray, Point2 outer, Point2 inner, bool mirror, EyePatch& out) {
    const float dx = inner.x - outer.x, dy = inner.y - outer.y;
    const float length = std::hypot(dx, dy);
    if (!std::isfinite(length) || length < 2.f || gray.empty()) return false;
    // Patch = s R M (image - outer) + (kOuterX, kCornerY), M = diag(-1, 1) when mirrored.
    const float m = mirror ? -1.f : 1.f;
    const float ux = m * dx / length, uy = dy / length;  // the corner axis after mirroring
    const float s = kEyeWidth / length;
    // Rotation taking (ux, uy) to (1, 0): [ux uy; -uy ux].
    const cv::Matx22f a(s * ux * m, s * uy, -s * uy * m, s * ux);
    const cv::Vec2f t = cv::Vec2f(kOuterX, kCornerY) - a * cv::Vec2f(outer.x, outer.y);
    out.patch_from_image = cv::Matx23f(a(0, 0), a(0, 1), t[0], a(1, 0), a(1, 1), t[1]);
    const cv::Matx22f inverse = a.inv();
    const cv::Vec2f back = -(inverse * t);
    out.image_from_patch = cv::Matx23f(inverse(0, 0), inverse(0, 1), back[0], inverse(1, 0), inverse(1, 1), back[1]);
    out.image_px_per_patch_px = 1.f / s;
    out.mirrored = mirror;

    // Bilinear sampling, the border repeated; by hand: OpenCV's warpAffine
    // and meanStdDev allocate scratch memory on every call.
    out.pixels.create(kPatchHeight, kPatchWidth, CV_32F);
    const cv::Matx23f& back_map = out.image_from_patch;
    const int w = gray.cols, h = gray.rows;
    // The sample points span the parallelogram of the patch's corner pixels: when it lies inside
    // the frame, no sample needs its neighbours clamped (the same values; the gaze stage ~7 % faster).
    bool inside = true;
    for (const int y : {0, kPatchHeight - 1}) {
        for (const int x : {0, kPatchWidth - 1}) {
            const float sx = back_map(0, 0) * x + back_map(0, 1) * y + back_map(0, 2);
            const float sy = back_map(1, 0) * x + back_map(1, 1) * y + back_map(1, 2);
            inside = inside && sx >= 1.f && sy >= 1.f && sx < static_cast<float>(w - 3) && sy < static_cast<float>(h - 3);
        }
    }
    const float a00 = back_map(0, 0), a01 = back_map(0, 1), a02 = back_map(0, 2);
    const float a10 = back_map(1, 0), a11 = back_map(1, 1), a12 = back_map(1, 2);
    const bool gather = inside && core::gathersFit(gray);
    double sum = 0.0, sumSquares = 0.0;
    for (int y = 0; y < kPatchHeight; ++y) {
        float* row = out.pixels.ptr<float>(y);
#if defined(__x86_64__)
        if (gather) sampleRowAvx2(gray, back_map, y, row);
#endif
        for (int x = 0; x < (gather ? 0 : kPatchWidth); ++x) {
            const float sx = a00 * static_cast<float>(x) + a01 * static_cast<float>(y) + a02;
            const float sy = a10 * static_cast<float>(x) + a11 * static_cast<float>(y) + a12;
            // Inside, the floor is the truncation and the neighbours are in the frame.
            int x0, y0, x1, y1;
            float ax, ay;
            if (inside) {
                x0 = static_cast<int>(sx), y0 = static_cast<int>(sy), x1 = x0 + 1, y1 = y0 + 1;
                ax = sx - static_cast<float>(x0), ay = sy - static_cast<float>(y0);
            } else {
                const float floorX = std::floor(sx), floorY = std::floor(sy);
                const int fx = static_cast<int>(floorX), fy = static_cast<int>(floorY);
                x0 = std::clamp(fx, 0, w - 1), x1 = std::clamp(fx + 1, 0, w - 1);
                y0 = std::clamp(fy, 0, h - 1), y1 = std::clamp(fy + 1, 0, h - 1);
                ax = sx - floorX, ay = sy - floorY;
            }
            const std::uint8_t* r0 = gray.ptr<std::uint8_t>(y0);
            const std::uint8_t* r1 = gray.ptr<std::uint8_t>(y1);
            row[x] = (1.f - ay) * ((1.f - ax) * r0[x0] + ax * r0[x1]) + ay * ((1.f - ax) * r1[x0] + ax * r1[x1]);
        }
        // A row's sums in float are exact enough (40 values <= 255); across rows in double. Four
        // partial sums each: one chain of dependent additions per pixel was a third of the cut's time.
        float rowSum[4] = {0.f, 0.f, 0.f, 0.f}, rowSquares[4] = {0.f, 0.f, 0.f, 0.f};
        for (int x = 0; x < kPatchWidth; x += 4) {
            for (int k = 0; k < 4; ++k) {
                rowSum[k] += row[x + k];
                rowSquares[k] += row[x + k] * row[x + k];
            }
        }
        sum += static_cast<double>((rowSum[0] + rowSum[1]) + (rowSum[2] + rowSum[3]));
        sumSquares += static_cast<double>((rowSquares[0] + rowSquares[1]) + (rowSquares[2] + rowSquares[3]));
    }
    static_assert(kPatchWidth % 4 == 0, "a row's sums run in fours");
    const double count = static_cast<double>(kPatchWidth * kPatchHeight);
    const double mean = sum / count;
    // A flat patch (a covered eye) keeps a floor on the deviation: noise is not amplified into texture.
    const double deviation = std::max(std::sqrt(std::max(0.0, sumSquares / count - mean * mean)), 4.0);
    const float scale = static_cast<float>(1.0 / deviation), offset = static_cast<float>(-mean / deviation);
    for (int y = 0; y < kPatchHeight; ++y) {
        float* row = out.pixels.ptr<float>(y);
        for (int x = 0; x < kPatchWidth; ++x) row[x] = row[x] * scale + offset;
    }
    return true;
}

Point2 toPatch(const EyePatch& p, Point2 image) {
    const cv::Matx23f& a = p.patch_from_image;
    return {a(0, 0) * image.x + a(0, 1) * image.y + a(0, 2), a(1, 0) * image.x + a(1, 1) * image.y + a(1, 2)};
}

Point2 toImage(const EyePatch& p, Point2 q) {
    const cv::Matx23f& a = p.image_from_patch;
    return {a(0, 0) * q.x + a(0, 1) * q.y + a(0, 2), a(1, 0) * q.x + a(1, 1) * q.y + a(1, 2)};
}

}  // namespace facetrack::gaze
