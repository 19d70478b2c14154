#pragma once
/// \file
/// Library version, where facetrack looks for its models, and its log.
/// All of these may be called from any thread.

#include <functional>
#include <string>

namespace facetrack {

/// "major.minor.patch".
const char* versionString();

/// The directory facetrack loads its shipped models from: the
/// FACETRACK_MODEL_DIR environment variable when set, else share/facetrack/models
/// beside the program's bin/ (an installed prefix, also after moving it),
/// else the install location configured at build time, else a models/ holding
/// face_model.ftm in or above the program's or the working directory (a
/// source tree's build). No build-tree path is compiled in.
std::string modelDirectory();

/// Receives facetrack's log lines (which detector is in use, fallbacks).
/// The default writes them to stderr prefixed with "facetrack: ". Pass an
/// empty function to silence them.
void setLogHandler(std::function<void(const std::string&)> handler);

}  // namespace facetrack
