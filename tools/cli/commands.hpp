#pragma once
// The facetrack CLI's subcommands. Each returns the process exit code and
// throws facetrack::Error for a one-line message on stderr.

#include "app/args.hpp"
#include "app/media.hpp"
#include "app/overlay.hpp"
#include "app/tracking_options.hpp"

#include "core/environment.hpp"
#include "facetrack/detector.hpp"
#include "facetrack/tracker.hpp"
#include "facetrack/version.hpp"

#include <filesystem>

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
int runCalibrate(const std::vector<std::string>& argv);
int runEvalGaze(const std::vector<std::string>& argv);
int runEvalExpressions(const std::vector<std::string>& argv);

/// A clip by the name ../shared/data/clips (`shared`) gives it, as labels and teacher files name
/// clips, or by its path. Error when no such file exists, before any video backend is asked (they
/// try every plugin on a missing file, and some leak doing it).
inline std::string clipPath(const std::string& shared, const std::string& clip) {
    const std::string path = std::filesystem::path(clip).has_parent_path() ? clip : shared + "/data/clips/" + clip;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw Error("no such clip: '" + path + "'");
    return path;
}

/// The expression labels (data/expression_labels.csv): --labels, else the repository's file, from
/// the working directory or beside the models/ folder in use.
inline std::string labelsPath(const tools::Args& args) {
    const std::string found = core::firstExistingFile({"data/expression_labels.csv", modelDirectory() + "/../data/expression_labels.csv"});
    return args.get("--labels", found.empty() ? "data/expression_labels.csv" : found);
}

// The tools' shared pieces, by their short names.
using tools::Args;
using tools::detectorConfig;
using tools::isImageFile;
using tools::kDetectorOptions;
using tools::kTrackerOptions;
using tools::listImages;
using tools::MediaFrame;
using tools::MediaReader;
using tools::OverlayRenderer;
using tools::parseSize;
using tools::readAllFrames;
using tools::trackerConfig;
using tools::trackingFlags;
using tools::trackingOptions;

}  // namespace facetrack::cli
