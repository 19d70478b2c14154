#include "eval_gaze_synthetic.hpp"

#include <cstdio>

namespace facetrack::cli {

void evalSyntheticGaze(int, const TrackerConfig&) { std::printf("synthetic: not built yet\n"); }

}  // namespace facetrack::cli
