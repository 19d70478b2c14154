#pragma once
// Where the 300-W annotators' 68 landmarks sit on the face model: an offset
// per landmark from the model's own landmark vertex (tools/train_convention
// learns them, docs/expressions.md). The fit adds them to its basis, so a
// relaxed face's 300-W-style landmarks fit a neutral expression. Jaw
// landmarks (0-16) slide along the silhouette and keep a zero offset.

#include "model/face_model_data.hpp"

#include <Eigen/Core>

#include <string>

namespace facetrack::fit {

struct FitBasis;

struct LandmarkConvention {
    /// Per landmark, in the fit basis's frontal frame (cm), like FitBasis::neutral.
    Eigen::Matrix<double, 3, model::kLandmarkCount> offsets_frontal_cm =
        Eigen::Matrix<double, 3, model::kLandmarkCount>::Zero();
};

constexpr char kConventionMagic[] = "FTCONV01";
constexpr std::uint32_t kConventionVersion = 1;

void writeLandmarkConvention(const std::string& path, const LandmarkConvention& convention);
/// Throws Error naming the file when it is missing, truncated or corrupt
/// (offsets not finite or over 3 cm).
LandmarkConvention readLandmarkConvention(const std::string& path);

/// Moves the basis's landmark slots by the convention's offsets.
void applyConvention(FitBasis& basis, const LandmarkConvention& convention);

}  // namespace facetrack::fit
