#pragma once
// What an eye model file holds (facetrack/eye_model.hpp), and its file format.

#include "gaze/patch_forest.hpp"

#include <cstdint>
#include <string>

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

struct EyeModelData {
    PatchForest pixels;     ///< anchor: the pixel; outputs P(skin), P(sclera), P(iris)
    PatchForest aperture;   ///< anchor: the patch origin; output: lid aperture / eye width
    /// What the aperture forest says, on eyes it was not trained on, for open
    /// eyes (the median; openness 1 until a face's own open-eye value is known)
    /// and for closed ones (teacher aperture under 0.1: openness 0). A
    /// forest's averaging pulls its extremes in; these undo that.
    float open_aperture = 0.3f;
    float closed_aperture = 0.1f;
    std::string provenance;
};

constexpr char kEyeModelMagic[] = "FTEYES01";
constexpr std::uint32_t kEyeModelVersion = 1;

void writeEyeModel(const std::string& path, const EyeModelData& model);
/// Throws Error naming the file when it is missing, truncated or corrupt.
EyeModelData readEyeModel(const std::string& path);

}  // namespace facetrack::gaze
