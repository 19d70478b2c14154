#pragma once
// What a landmark refiner file holds (facetrack/refiner_model.hpp), and its file format.

#include <cstdint>
#include <string>
#include <vector>

namespace facetrack::nn {

struct RefinerModelData {
    /// The landmark refiner (refine/landmark_refiner.hpp): ONNX bytes.
    std::string net;
    int patch_size = 0;
    std::vector<float> mean;   ///< 136: the mean shape in patch pixels, x0, y0, x1, ...
    std::vector<float> share;  ///< 68: per landmark, the net's share of the answer, the rest LBF's
    /// Where the net takes the whole answer as it disagrees with LBF (landmark_refiner.hpp: D0, D1).
    /// D1 <= D0: never.
    float trust_from = 0.f, trust_to = 0.f;
    /// The brow and eye refiner (landmark_refiner.hpp, "one side at a time"): ONNX bytes, or empty
    /// for none. It runs on the landmark refiner's answer.
    std::string side_net;
    int side_patch_size = 0;
    std::vector<float> side_mean;   ///< 22: one side's 11 points (kRightSide's order) in patch pixels
    std::vector<float> side_share;  ///< 11: per point, the net's share of the answer
    std::string provenance;
};

constexpr char kRefinerModelMagic[] = "FTLMREFN";
constexpr std::uint32_t kRefinerModelVersion = 1;

/// Throws Error naming the file when `model` is not a valid refiner or the file cannot be written.
void writeRefinerModel(const std::string& path, const RefinerModelData& model);
/// Throws Error naming the file when it is missing, truncated or corrupt.
RefinerModelData readRefinerModel(const std::string& path);

}  // namespace facetrack::nn
