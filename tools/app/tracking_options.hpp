#pragma once
// The detector's and the tracker's command-line options, shared by every tool
// that tracks (the CLI's track, bench and eval-track, and the demo).

#include "app/args.hpp"

#include "facetrack/detector.hpp"
#include "facetrack/tracker.hpp"

#include <set>
#include <string>

namespace facetrack::tools {

/// --detector auto|yunet|cascade, --yunet PATH, --min-score S.
inline const std::set<std::string> kDetectorOptions = {"--detector", "--yunet", "--min-score"};
DetectorConfig detectorConfig(const Args& args);

/// --max-faces N, --fov DEG, --focal PX, --calibration-frames N, --expression-prior F,
/// --landmark-starts N, --filter-cutoff HZ, --filter-beta B, --refiner FILE|none, --cnn FILE|none, --eyes FILE|none, and
/// the flags --no-filter,
/// --no-cnn-stage.
inline const std::set<std::string> kTrackerOptions = {"--max-faces",
                                                      "--fov",
                                                      "--focal",
                                                      "--calibration-frames",
                                                      "--expression-prior",
                                                      "--landmark-starts",
                                                      "--filter-cutoff",
                                                      "--filter-beta",
                                                      "--refiner",
                                                      "--cnn",
                                                      "--eyes"};
inline const std::set<std::string> kTrackerFlags = {"--no-filter", "--no-cnn-stage"};
/// Every value is checked here (facetrack::validate): commands call it, and load their models,
/// before they open any input, so that a bad option is the error, not the input.
TrackerConfig trackerConfig(const Args& args);

/// The shipped models (Models::loadDefault), the landmark refiner replaced by --refiner FILE, or
/// left out with --refiner none; the CNN file and the eye model likewise by --cnn and --eyes.
Models trackingModels(const Args& args);

/// --profile FILE|none, for the commands a user tracks themself with (track, send, the demo):
/// the user's calibration (facetrack/calibration.hpp) from FILE; without the option, from
/// defaultProfilePath() when a profile is there; "none": no calibration. Says on stderr which
/// profile it uses. A profile that cannot be read is an Error naming it.
Calibration userCalibration(const Args& args);

/// The options of a command that tracks: the detector's and the tracker's, plus `more`.
std::set<std::string> trackingOptions(std::set<std::string> more);
/// Its flags: the tracker's (kTrackerFlags), plus `more`.
std::set<std::string> trackingFlags(std::set<std::string> more);

}  // namespace facetrack::tools
