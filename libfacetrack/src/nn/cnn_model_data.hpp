#pragma once
// What a CNN cascade file holds (facetrack/cnn_model.hpp), and its file format.

#include <cstdint>
#include <string>
#include <vector>

namespace facetrack::nn {

struct CnnStageData {
    int rounds = 1;    ///< how many times the stage runs, re-warping in between
    std::string onnx;  ///< the net, an ONNX file's bytes (opset <= 13; update_net.hpp says what it computes)
};

/// The geometry net's inputs (expression/geometry_net.hpp): the 68 normalised points' x and y, then
/// sin(pitch) and sin(yaw).
constexpr int kGeometryFeatures = 2 * 68 + 2;
/// The lip net's points (expression/lip_net.hpp): 40 of MediaPipe Face Landmarker's mesh, whose
/// x and y the geometry net reads after its own features when the file has a lip net.
constexpr int kLipPoints = 40;

/// A dense layer, y = W x + b, W `rows` x `cols` row-major.
struct DenseLayer {
    int rows = 0, cols = 0;
    std::vector<float> weight, bias;
};

struct CnnModelData {
    int patch_size = 64;
    /// The nets' expression outputs, native face model names, in output order.
    std::vector<std::string> expressions;
    std::vector<CnnStageData> stages;
    /// The nets were trained to read the expressions (train_stage.py --expressions): the stage then
    /// keeps the fit's pose and the shapes the fit estimates, and reports the others. False: it
    /// refines the pose and all its expressions. (Format version 3; version 2 files refine.)
    bool expressions_only = false;
    /// With expressions_only: the stage also writes the shapes the fit estimates, the fit's value
    /// moved by the net's update, then rescaled by the neutral below like every shape it reports:
    /// the nets' training starts were the fit's answers (make_cnn_samples --starts-from fit), so the
    /// update is a correction of the fit, and their labels (the blendshape teacher's) read each
    /// shape from its own rest level. Format version 7.
    bool corrects_fit = false;
    /// Per expression (empty: none), w0, what the net reads on a face that does not show the shape.
    /// The stage reports (w - w0) / (1 - w0), clamped to [0, 1]: the labels read browDown 0.23 on
    /// the median face, and a net trained on them does the same on a relaxed one (docs/cnn.md).
    /// pack_cnn sets it to the labels' median over the 300-W training crops (--neutral-from), or to
    /// the net's rest level on the validation crops (--rest-from-validation), which also keeps its
    /// noise on relaxed faces out. Format version 3.
    std::vector<float> neutral;
    /// Per expression (empty: 1 for all), w1, what the net reads on a face that shows the shape
    /// fully: the stage reports (w - w0) / (w1 - w0), clamped to [0, 1]. A net regresses the rare,
    /// strong expressions of faces it has not seen towards the mean; pack_cnn sets w1 = w0 + (1 - w0) / g
    /// from each shape's gain g on the validation people (--gain-from-validation). Format version 8.
    std::vector<float> full;
    /// Per expression (empty: all), whether an expressions-only stage reports it: the packer keeps
    /// those whose estimate agreed with the labels on the validation crops (docs/cnn.md). Version 3.
    std::vector<bool> reported;
    /// The stages read each patch and its mirror image and apply the mean update (update_net.hpp,
    /// refine): the face and its mirror image read alike. Their nets then need each sided
    /// expression's partner among `expressions`. Format version 7.
    bool mirror_averaged = false;
    /// The geometry net (expression/geometry_net.hpp; format version 9): dense layers, ReLU between
    /// them and a sigmoid after the last, from the landmarks' geometry to `expressions`; empty: none.
    std::vector<DenseLayer> geometry_net;
    /// Per expression (empty: none), whether the stage reports the geometry net's reading in place
    /// of the texture nets': pack_cnn keeps those whose geometry reading agreed better with the
    /// labels on the validation people. Each is read between its own neutral and full readings below.
    std::vector<bool> geometry_reported;
    std::vector<float> geometry_neutral, geometry_full;
    /// The lip net (expression/lip_net.hpp; format version 11): ONNX bytes of a net of batch 2 from a
    /// mouth patch of `lip_patch_size` pixels spanning 2 `lip_patch_half` normalised units to the 40
    /// lip points; empty: none. With it the geometry net's inputs are its own and the points' x, y.
    std::string lip_net;
    int lip_patch_size = 64;
    float lip_patch_half = 0.75f;
    /// The final net, the 68 landmarks' displacements (landmark_net.hpp): ONNX bytes, or empty for none.
    std::string landmark_net;
    std::string provenance;
};

constexpr char kCnnModelMagic[] = "FTCNNCAS";
/// Versions 4-9 also held the landmark refiner, now a file of its own (refiner_model_data.hpp):
/// the reader skips it.
constexpr std::uint32_t kCnnModelVersion = 11;

void writeCnnModel(const std::string& path, const CnnModelData& model);

/// Indices into FaceModel::expressionNames() of `names`; throws Error naming one the model lacks.
std::vector<int> expressionIndices(const std::vector<std::string>& modelNames, const std::vector<std::string>& names);
/// Throws Error naming the file when it is missing, truncated or corrupt.
CnnModelData readCnnModel(const std::string& path);

}  // namespace facetrack::nn
