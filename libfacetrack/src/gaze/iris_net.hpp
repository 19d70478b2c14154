#pragma once
// The pixel classifier as a small CNN (eye_model_data.hpp, `iris_net`): both
// eyes' patches in one call, P(skin), P(sclera), P(iris) on a stride-2 grid,
// of which the gaze fit reads the classified region's cells, as it reads the
// pixel forest's.

#include "nn/onnx_net.hpp"

#include <opencv2/core.hpp>

#include <array>
#include <string>

namespace facetrack::gaze {

class IrisNet {
public:
    /// Throws Error (naming `what`) when the net does not load or does not map
    /// 2 x 1 x 28 x 40 to 2 x 3 x 14 x 20.
    IrisNet(const std::string& onnx, const std::string& what);

    /// For each eye whose patch is given (CV_32F, kPatchHeight x kPatchWidth,
    /// normalised): P(iris) and P(open) = P(sclera) + P(iris) on
    /// kClassifiedRegion's cells, into `iris[e]` and `open[e]` (CV_32F,
    /// rows() x columns(), allocated by the caller). Not thread-safe.
    void classify(const std::array<const cv::Mat*, 2>& patches, const std::array<cv::Mat*, 2>& iris, const std::array<cv::Mat*, 2>& open);

    /// What runs the net (nn::OnnxNet::engineName).
    const char* engineName() const { return net_.engineName(); }

private:
    nn::OnnxNet net_;
};

}  // namespace facetrack::gaze
