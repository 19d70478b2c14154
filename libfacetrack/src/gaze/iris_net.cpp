#include "gaze/iris_net.hpp"

#include "gaze/eye_model_data.hpp"

#include <cstring>

namespace facetrack::gaze {

namespace {
constexpr int kCells = kIrisNetRows * kIrisNetColumns;
}

IrisNet::IrisNet(const std::string& onnx, const std::string& what)
    : net_(onnx, {2, 1, kPatchHeight, kPatchWidth}, 2 * kPixelClasses * kCells, what) {}

void IrisNet::classify(const std::array<const cv::Mat*, 2>& patches, const std::array<cv::Mat*, 2>& iris,
                       const std::array<cv::Mat*, 2>& open) {
    float* input = net_.input().ptr<float>();
    constexpr int kPixels = kPatchHeight * kPatchWidth;
    for (std::size_t e = 0; e < 2; ++e) {
        float* plane = input + e * kPixels;
        const cv::Mat* p = patches[e];
        if (!p) {
            std::memset(plane, 0, sizeof(float) * kPixels);
            continue;
        }
        for (int y = 0; y < kPatchHeight; ++y) std::memcpy(plane + y * kPatchWidth, p->ptr<float>(y), sizeof(float) * kPatchWidth);
    }
    const float* out = net_.forward();
    constexpr PatchRegion r = kClassifiedRegion;
    for (std::size_t e = 0; e < 2; ++e) {
        if (!patches[e]) continue;
        const float* sclera = out + (e * kPixelClasses + kSclera) * kCells;
        const float* pIris = out + (e * kPixelClasses + kIris) * kCells;
        for (int j = 0; j < r.rows(); ++j) {
            const int row = r.y(j) / 2;
            float* irisRow = iris[e]->ptr<float>(j);
            float* openRow = open[e]->ptr<float>(j);
            for (int i = 0; i < r.columns(); ++i) {
                const int cell = row * kIrisNetColumns + r.x(i) / 2;
                irisRow[i] = pIris[cell];
                openRow[i] = pIris[cell] + sclera[cell];
            }
        }
    }
}

}  // namespace facetrack::gaze
