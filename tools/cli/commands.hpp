#pragma once
// The facetrack CLI's subcommands. Each returns the process exit code and
// throws facetrack::Error for a one-line message on stderr.

#include "args.hpp"

#include "facetrack/detector.hpp"

#include <cmath>

namespace facetrack::cli {

int runInfo(const std::vector<std::string>& argv);
int runDetect(const std::vector<std::string>& argv);
int runTrack(const std::vector<std::string>& argv);
int runEvalDetect(const std::vector<std::string>& argv);

/// --detector auto|yunet|cascade, --yunet PATH, --min-score S: shared by every
/// command that detects.
inline const std::set<std::string> kDetectorOptions = {"--detector", "--yunet", "--min-score"};
DetectorConfig detectorConfig(const Args& args);

/// A number rounded to 1/100 (pixels, scores, ms) for readable JSON.
inline double round2(double v) { return std::round(v * 100.0) / 100.0; }

}  // namespace facetrack::cli
