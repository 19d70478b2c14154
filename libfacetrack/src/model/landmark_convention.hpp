#pragma once
// What the landmark fit learns from data (tools/train/convention,
// docs/expressions.md):
// - where the 300-W annotators' 68 landmarks sit on the face model: an offset
//   per landmark from the model's own landmark vertex. The fit adds them to
//   its basis, so a relaxed face's 300-W-style landmarks fit a neutral
//   expression. Jaw landmarks (0-16) slide along the silhouette and keep a
//   zero offset;
// - the expression prior: per fitted expression j a factor f_j on the fit's
//   w_l2, from the dense teacher labels' second moments, f_j ~ 1 / E[b_j^2]
//   (a zero-mean Gaussian prior with each shape's own spread: shapes faces
//   often show are held back less than rare ones).

#include "model/face_model_data.hpp"

#include <Eigen/Core>

#include <map>
#include <string>

namespace facetrack::model {

struct LandmarkConvention {
    /// Per landmark, in the fit basis's frontal frame (cm), like FitBasis::neutral.
    Eigen::Matrix<double, 3, kLandmarkCount> offsets_frontal_cm = Eigen::Matrix<double, 3, kLandmarkCount>::Zero();
    /// Native expression name -> f_j; a fitted expression not listed keeps 1.
    std::map<std::string, double> expression_prior;
};

constexpr char kConventionMagic[] = "FTCONV01";
constexpr std::uint32_t kConventionVersion = 2;

void writeLandmarkConvention(const std::string& path, const LandmarkConvention& convention);
/// Throws Error naming the file when it is missing, truncated or corrupt
/// (offsets not finite or over 3 cm, prior factors not finite and positive).
LandmarkConvention readLandmarkConvention(const std::string& path);

}  // namespace facetrack::model
