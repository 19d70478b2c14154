#pragma once
// The facetrack CLI's subcommands. Each returns the process exit code and
// throws facetrack::Error for a one-line message on stderr.

#include "args.hpp"

#include "facetrack/detector.hpp"

namespace facetrack::cli {

int runInfo(const std::vector<std::string>& argv);
int runDetect(const std::vector<std::string>& argv);
int runTrack(const std::vector<std::string>& argv);
int runEvalDetect(const std::vector<std::string>& argv);
int runLandmarks(const std::vector<std::string>& argv);
int runEvalLandmarks(const std::vector<std::string>& argv);

/// --detector auto|yunet|cascade, --yunet PATH, --min-score S: shared by every
/// command that detects.
inline const std::set<std::string> kDetectorOptions = {"--detector", "--yunet", "--min-score"};
DetectorConfig detectorConfig(const Args& args);

}  // namespace facetrack::cli
