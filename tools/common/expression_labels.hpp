#pragma once
// data/expression_labels.csv: expression segments of ../shared/data/clips,
// labelled by eye (docs/expressions.md). Read by eval-expressions (the
// figures) and by `facetrack calibrate` (a clip's labelled segments as the
// guided capture's prompts).

#include <string>
#include <vector>

namespace facetrack::tools {

struct LabelledSegment {
    std::string clip;         ///< a file name of ../shared/data/clips
    int first = 0, last = 0;  ///< frames, 0-based in decode order, inclusive
    std::string label;        ///< "neutral", "smile", "pucker", ...
};

/// Every segment of the file, in its order ('#' lines and the header skipped).
/// Throws Error naming the file and line when one is not clip,first,last,label
/// with first <= last.
std::vector<LabelledSegment> readExpressionLabels(const std::string& path = "data/expression_labels.csv");

}  // namespace facetrack::tools
