#pragma once
// ../shared/data/teacher/clips_blendshapes.csv: MediaPipe Face Landmarker's
// blendshape scores for every clip frame (../shared/tools/blendshape-teacher).
// Another model's predictions, not ground truth. Read by eval-expressions (the
// teacher's bars beside ours) and eval-gaze (its eyeBlink beside its lids).

#include "facetrack/arkit.hpp"

#include <array>
#include <map>
#include <string>

namespace facetrack::tools {

/// ARKit-ordered scores; tongueOut, which MediaPipe lacks, stays 0.
using BlendshapeScores = std::array<float, kArkitBlendshapeCount>;

/// Keyed by teacherKey(clip, frame); frames where it found no face are left
/// out. Throws Error naming the file when it cannot be read or a row is short.
std::map<std::string, BlendshapeScores> readBlendshapeTeacher(const std::string& csvPath);

}  // namespace facetrack::tools
