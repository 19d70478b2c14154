#pragma once
// Where things are: model and data directories, environment variables, logging.

#include <string>
#include <vector>

namespace facetrack::core {

/// The value of an environment variable, or "" when unset.
std::string getEnv(const char* name);

/// The first path of the list that names an existing regular file, or "".
std::string firstExistingFile(const std::vector<std::string>& candidates);

/// The shared data folder (../shared): FACETRACK_SHARED_DIR, else a ../shared
/// (holding data/ or models/) seen from the program's directory, the working
/// directory, or any directory above them; "" when none exists.
std::string sharedDirectory();

/// Sends a line to the log handler (see facetrack::setLogHandler).
void log(const std::string& line);

}  // namespace facetrack::core
