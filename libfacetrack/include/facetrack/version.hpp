#pragma once
/// \file
/// Library version and where facetrack looks for its models.

#include <functional>
#include <string>

namespace facetrack {

/// "major.minor.patch".
const char* versionString();

/// The directory facetrack loads its shipped models from: the
/// FACETRACK_MODEL_DIR environment variable when set, else the installed
/// share/facetrack/models, else the source tree's models/ (for builds that
/// are not installed).
std::string modelDirectory();

/// Receives facetrack's log lines (which detector is in use, fallbacks).
/// The default writes them to stderr prefixed with "facetrack: ". Pass an
/// empty function to silence them.
void setLogHandler(std::function<void(const std::string&)> handler);

}  // namespace facetrack
