#pragma once
// The facetrack CLI's subcommands. Each returns the process exit code and
// throws facetrack::Error for a one-line message on stderr.

#include "app/args.hpp"
#include "app/media.hpp"
#include "app/overlay.hpp"
#include "app/tracking_options.hpp"

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
int runSend(const std::vector<std::string>& argv);
int runEvalGaze(const std::vector<std::string>& argv);
int runEvalExpressions(const std::vector<std::string>& argv);

// The tools' shared pieces, by their short names.
using tools::Args;
using tools::detectorConfig;
using tools::kDetectorOptions;
using tools::kTrackerFlags;
using tools::kTrackerOptions;
using tools::trackerConfig;
using tools::trackingOptions;
using tools::MediaFrame;
using tools::MediaReader;
using tools::OverlayRenderer;
using tools::isImageFile;
using tools::listImages;
using tools::parseSize;
using tools::readAllFrames;

}  // namespace facetrack::cli
