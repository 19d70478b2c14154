#pragma once
// What an eye model file holds (facetrack/eye_model.hpp), and its file format.

#include "gaze/eye_patch.hpp"
#include "gaze/patch_forest.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace facetrack::gaze {

/// Where in the patch the pixel classifier runs: the eye and its lids, on a
/// grid of every `step`-th pixel (the iris is about 12 patch pixels across).
struct PatchRegion {
    int x0 = 2, x1 = 38, y0 = 4, y1 = 24, step = 2;
    constexpr int columns() const { return (x1 - x0 + step - 1) / step; }
    constexpr int rows() const { return (y1 - y0 + step - 1) / step; }
    /// Patch coordinates of grid cell (i, j).
    constexpr int x(int i) const { return x0 + step * i; }
    constexpr int y(int j) const { return y0 + step * j; }
};
constexpr PatchRegion kClassifiedRegion{};

enum PixelClass { kSkin = 0, kSclera = 1, kIris = 2, kPixelClasses = 3 };

/// The iris net's output grid: stride 2 over the whole patch, cell (j, i) at
/// patch pixel (2i, 2j); kClassifiedRegion's cells are among them.
constexpr int kIrisNetRows = kPatchHeight / 2;
constexpr int kIrisNetColumns = kPatchWidth / 2;
static_assert(kClassifiedRegion.step == 2 && kClassifiedRegion.x0 % 2 == 0 && kClassifiedRegion.y0 % 2 == 0,
              "the classified region's cells must be cells of the iris net's grid");

struct EyeModelData {
    PatchForest pixels;    ///< anchor: the pixel; outputs P(skin), P(sclera), P(iris)
    PatchForest aperture;  ///< anchor: the patch origin; output: lid aperture / eye width
    /// What the aperture forest says, on eyes it was not trained on, for open
    /// eyes (the median; openness 1 until a face's own open-eye value is known)
    /// and for closed ones (teacher aperture under 0.1: openness 0). A
    /// forest's averaging pulls its extremes in; these undo that.
    float open_aperture = 0.3f;
    float closed_aperture = 0.1f;
    std::string provenance;
    /// Optional (file version 2): an ONNX CNN that replaces the pixel forest:
    /// N x 1 x 28 x 40 normalised patches -> N x 3 x 14 x 20 class
    /// probabilities (skin, sclera, iris) on the grid above
    /// (tools/train/eyes/train_iris_net.py). Empty: the pixel forest classifies.
    std::string iris_net;
    /// Optional (file version 3): the eye corners refined from the patch, a
    /// cascade of forests. Anchor: the patch origin; outputs: the outer and
    /// the inner corner's offsets (x, y) from (kOuterX, kCornerY) and
    /// (kInnerX, kCornerY) in patch pixels; each stage reads a patch re-cut at
    /// the previous one's corners. Trained on the 300-W annotators' corners
    /// and renders' exact ones (train_eyes). Empty: the landmarks' corners.
    std::vector<PatchForest> corner_stages;
    /// Optional (file version 4): the open map's lid gap (openMapGap) read on
    /// the pixel forest's scale, a * gap + b. The openness was tuned on the
    /// forest's map (a = 1, b = 0); an iris net's map spreads wider (a
    /// half-lidded eye reads narrower, an open one wider), so train_eyes
    /// --iris-net fits a and b by least squares of the forest map's gap on the
    /// net's over the training clips' eyes (docs/gaze.md).
    float open_map_scale = 1.f;
    float open_map_offset = 0.f;
    /// Optional (file version 4): the iris net's maps are averaged over a box of
    /// (2r + 1)^2 grid cells before the fit reads them (0: as the net gives
    /// them). The net's maps change more sharply from cell to cell than the
    /// forest's (their mean squared step is 1.5x the forest's on the training
    /// clips); read unsmoothed, a small face turned 20 degrees and looking down
    /// held too small a pitch and read as a blink (docs/decisions.md, "Eyes").
    int net_map_radius = 0;
};

/// At most this box radius (a file with a larger one is corrupt).
constexpr int kMaxNetMapRadius = 3;

/// `map` (kClassifiedRegion's size, CV_32F) averaged in place over a box of
/// (2 radius + 1)^2 cells, the borders repeated. Allocates nothing.
void boxSmooth(cv::Mat& map, int radius);

class IrisNet;

/// P(iris) and P(open) of the eyes whose patch is given, by the model's iris
/// net `net` (IrisNet::classify), each map then box-smoothed by the model's
/// net_map_radius: the maps the gaze fit reads.
void classifyByNet(const EyeModelData& model, IrisNet& net, const std::array<const cv::Mat*, 2>& patches,
                   const std::array<cv::Mat*, 2>& iris, const std::array<cv::Mat*, 2>& open);

/// The lid gap the classifier's open map `open` (kClassifiedRegion's cells)
/// shows, over the eye width, at 35, 50 and 65 % of the way from the outer
/// corner: the teacher's aperture (tools/common/teacher.hpp) measured on P_open.
float openMapGap(const cv::Mat& open);

/// openMapGap on the pixel forest's scale (EyeModelData::open_map_scale): a
/// second reading of the aperture beside the aperture forest's.
inline float openMapAperture(const EyeModelData& model, const cv::Mat& open) {
    return model.open_map_scale * openMapGap(open) + model.open_map_offset;
}

/// One stage of the corner cascade: the corners `patch` was cut at, moved by
/// `forest`'s reading of it (outer, inner; frame pixels).
std::array<Point2, 2> refineCorners(const PatchForest& forest, const EyePatch& patch);

/// An eye's outer and inner corners in the frame: those `patch` was cut at
/// (the landmarks'), refined by each of the model's corner stages, re-cutting
/// into `scratch` between stages. Why: the eyeballs are placed from the
/// corners, and 1 % of the inter-ocular distance there is about 2 degrees of
/// gaze (docs/gaze.md).
std::array<Point2, 2> eyeCorners(const EyeModelData& model, const cv::Mat& gray, const EyePatch& patch, EyePatch& scratch);

/// The pixel forest's tests reach at most this far from the classified pixel
/// (a file whose tests reach further is corrupt): classifyByForest pads the
/// patch by it once instead of clamping every read.
constexpr int kPixelTestReach = 8;

/// P(iris) and P(open) = P(sclera) + P(iris) of one normalised patch on
/// kClassifiedRegion's cells, by the pixel forest, into `iris` and `open`
/// (CV_32F, rows() x columns(), allocated by the caller); `padded` is scratch.
void classifyByForest(const EyeModelData& model, const cv::Mat& patch, cv::Mat& padded, cv::Mat& iris, cv::Mat& open);

/// At most this many corner stages (a file with more is corrupt).
constexpr std::size_t kMaxCornerStages = 4;

constexpr char kEyeModelMagic[] = "FTEYES01";
constexpr std::uint32_t kEyeModelVersion = 4;  ///< 1: no iris net; 2: no corner cascade; 3: no open-map scale or net-map box

void writeEyeModel(const std::string& path, const EyeModelData& model);
/// Throws Error naming the file when it is missing, truncated or corrupt.
EyeModelData readEyeModel(const std::string& path);

}  // namespace facetrack::gaze
