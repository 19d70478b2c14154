#pragma once
// The facetrack CLI's subcommands. Each returns the process exit code and
// throws facetrack::Error for a one-line message on stderr.

#include "args.hpp"

#include "facetrack/detector.hpp"
#include "facetrack/tracker.hpp"

namespace facetrack::cli {

int runInfo(const std::vector<std::string>& argv);
int runDetect(const std::vector<std::string>& argv);
int runTrack(const std::vector<std::string>& argv);
int runEvalDetect(const std::vector<std::string>& argv);
int runLandmarks(const std::vector<std::string>& argv);
int runEvalLandmarks(const std::vector<std::string>& argv);
int runBench(const std::vector<std::string>& argv);
int runEvalTrack(const std::vector<std::string>& argv);

/// --detector auto|yunet|cascade, --yunet PATH, --min-score S: shared by every
/// command that detects.
inline const std::set<std::string> kDetectorOptions = {"--detector", "--yunet", "--min-score"};
DetectorConfig detectorConfig(const Args& args);

/// The tracker's options, shared by track, bench and eval-track (plus the detector's):
/// --max-faces N, --fov DEG, --focal PX, --calibration-frames N, --filter-cutoff HZ,
/// --filter-beta B, and the flag --no-filter.
inline const std::set<std::string> kTrackerOptions = {"--max-faces", "--fov", "--focal", "--calibration-frames",
                                                      "--filter-cutoff", "--filter-beta"};
inline const std::set<std::string> kTrackerFlags = {"--no-filter"};
TrackerConfig trackerConfig(const Args& args);

/// The options of a command that tracks: the detector's and the tracker's, plus `more`.
std::set<std::string> trackingOptions(std::set<std::string> more);

}  // namespace facetrack::cli
