#pragma once
// What a CNN cascade file holds (facetrack/cnn_model.hpp), and its file format.

#include <cstdint>
#include <string>
#include <vector>

namespace facetrack::cnn {

struct CnnStageData {
    int rounds = 1;    ///< how many times the stage runs, re-warping in between
    std::string onnx;  ///< the net, an ONNX file's bytes (opset <= 13; update_net.hpp says what it computes)
};

struct CnnModelData {
    int patch_size = 64;
    /// The nets' expression outputs, native face model names, in output order.
    std::vector<std::string> expressions;
    std::vector<CnnStageData> stages;
    /// The final net, the 68 landmarks' displacements (landmark_net.hpp): ONNX bytes, or empty for none.
    std::string landmark_net;
    std::string provenance;
};

constexpr char kCnnModelMagic[] = "FTCNNCAS";
constexpr std::uint32_t kCnnModelVersion = 2;

void writeCnnModel(const std::string& path, const CnnModelData& model);

/// Indices into FaceModel::expressionNames() of `names`; throws Error naming one the model lacks.
std::vector<int> expressionIndices(const std::vector<std::string>& modelNames, const std::vector<std::string>& names);
/// Throws Error naming the file when it is missing, truncated or corrupt.
CnnModelData readCnnModel(const std::string& path);

}  // namespace facetrack::cnn
