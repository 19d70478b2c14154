#include "core/environment.hpp"

#include "facetrack/version.hpp"

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <mutex>

namespace fs = std::filesystem;

namespace facetrack {

const char* versionString() { return FACETRACK_VERSION; }

std::string modelDirectory() {
    const std::string fromEnv = core::getEnv("FACETRACK_MODEL_DIR");
    if (!fromEnv.empty()) return fromEnv;
    std::error_code ec;
    if (fs::is_directory(FACETRACK_INSTALL_MODEL_DIR, ec)) return FACETRACK_INSTALL_MODEL_DIR;
    return FACETRACK_SOURCE_DIR "/models";
}

namespace {
std::mutex logMutex;
std::function<void(const std::string&)>& logHandler() {
    static std::function<void(const std::string&)> handler = [](const std::string& line) {
        std::cerr << "facetrack: " << line << '\n';
    };
    return handler;
}
}  // namespace

void setLogHandler(std::function<void(const std::string&)> handler) {
    std::lock_guard<std::mutex> lock(logMutex);
    logHandler() = std::move(handler);
}

namespace core {

std::string getEnv(const char* name) {
    const char* value = std::getenv(name);
    return value ? value : "";
}

std::string firstExistingFile(const std::vector<std::string>& candidates) {
    for (const auto& path : candidates) {
        std::error_code ec;
        if (!path.empty() && fs::is_regular_file(path, ec)) return path;
    }
    return "";
}

std::string sharedDirectory() {
    for (const std::string& dir : {getEnv("FACETRACK_SHARED_DIR"), std::string("../shared"),
                                   std::string(FACETRACK_SOURCE_DIR "/../shared")}) {
        std::error_code ec;
        if (!dir.empty() && fs::is_directory(dir, ec)) return fs::weakly_canonical(dir, ec).string();
    }
    return "";
}

void log(const std::string& line) {
    std::lock_guard<std::mutex> lock(logMutex);
    if (logHandler()) logHandler()(line);
}

}  // namespace core
}  // namespace facetrack
