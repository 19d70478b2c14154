#pragma once
// The 300-W face crops of ../shared/data/faces300w and facetrack's fixed
// splits of them (docs/landmarks.md):
// - train: helen/trainset, lfpw/trainset and afw, minus validation;
// - validation: about 10 % of helen/trainset and lfpw/trainset, chosen by
//   source image (all faces of one photo fall on the same side), never trained on;
// - test: the 300-W common test set, helen/testset + lfpw/testset, never trained on.

#include "core/shape2d.hpp"
#include "facetrack/detector.hpp"

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace facetrack::tools {

struct AnnotatedImage {
    std::string image;   ///< path of the .jpg/.png
    std::string pts;     ///< path of its .pts
    std::string subset;  ///< "helen/trainset", "afw", ...
};

enum class Split { Train, Validation, Test };

Split parseSplit(const std::string& name);

/// `given` when not empty, else ../shared/data/faces300w; throws Error when neither exists.
std::string faces300wRoot(const std::string& given);  ///< "train", "validation", "test"

/// Every annotated image of the split, sorted by path. Throws Error when the
/// folder is missing or the split is empty.
std::vector<AnnotatedImage> list300W(const std::string& root, Split split);

/// Every image (.jpg, .jpeg, .png, .pgm) with a .pts beside it, below dir (any folder of annotated faces).
std::vector<AnnotatedImage> listAnnotated(const std::string& dir);

/// Whether a detector box is this annotated face: it contains the points'
/// centroid and its size, sqrt(w h), is 0.5-2x that of their bounding box.
bool boxMatchesFace(const Box& box, const core::Shape2& points);

/// Of the matching detections, the one overlapping the points' bounding box most.
std::optional<Box> matchingBox(const std::vector<Detection>& detections, const core::Shape2& points);

using core::kMirror68;

}  // namespace facetrack::tools
