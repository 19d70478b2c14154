#include "core/environment.hpp"

#include "facetrack/version.hpp"

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <mutex>

namespace fs = std::filesystem;

namespace facetrack {

const char* versionString() { return FACETRACK_VERSION; }

namespace {

/// The running program's directory ("" when unknown).
fs::path executableDirectory() {
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    return ec ? fs::path() : exe.parent_path();
}

/// `start` and each directory above it.
std::vector<fs::path> selfAndAncestors(fs::path start) {
    std::vector<fs::path> out;
    std::error_code ec;
    start = fs::weakly_canonical(start, ec);
    while (!start.empty()) {
        out.push_back(start);
        if (start == start.root_path()) break;
        start = start.parent_path();
    }
    return out;
}

/// Where a program of facetrack's own source tree or of an installed prefix
/// finds things without a path compiled in: its own directory, the working
/// directory, and the directories above them.
std::vector<fs::path> searchRoots() {
    std::vector<fs::path> roots;
    std::error_code ec;
    for (const fs::path& start : {executableDirectory(), fs::current_path(ec)}) {
        if (start.empty()) continue;
        for (const auto& dir : selfAndAncestors(start)) roots.push_back(dir);
    }
    return roots;
}

}  // namespace

std::string modelDirectory() {
    const std::string fromEnv = core::getEnv("FACETRACK_MODEL_DIR");
    if (!fromEnv.empty()) return fromEnv;
    std::error_code ec;
    // An installed prefix, where it was installed or moved as a whole (bin/ next to share/).
    const fs::path relocated = executableDirectory() / "../share/facetrack/models";
    if (fs::is_regular_file(relocated / "face_model.ftm", ec)) return fs::weakly_canonical(relocated, ec).string();
    if (fs::is_directory(FACETRACK_INSTALL_MODEL_DIR, ec)) return FACETRACK_INSTALL_MODEL_DIR;
    // facetrack's source tree: models/ above the build directory or the working directory.
    for (const auto& root : searchRoots()) {
        if (fs::is_regular_file(root / "models/face_model.ftm", ec)) return (root / "models").string();
    }
    return FACETRACK_INSTALL_MODEL_DIR;
}

namespace {
std::mutex logMutex;
std::function<void(const std::string&)>& logHandler() {
    static std::function<void(const std::string&)> handler = [](const std::string& line) { std::cerr << "facetrack: " << line << '\n'; };
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
    std::error_code ec;
    const std::string fromEnv = getEnv("FACETRACK_SHARED_DIR");
    if (!fromEnv.empty()) return fs::is_directory(fromEnv, ec) ? fs::weakly_canonical(fromEnv, ec).string() : "";
    // ../shared beside the source tree, seen from the working directory, the program, or above them.
    for (const auto& root : searchRoots()) {
        const fs::path dir = root / "../shared";
        if (fs::is_directory(dir / "data", ec) || fs::is_directory(dir / "models", ec)) return fs::weakly_canonical(dir, ec).string();
    }
    return "";
}

void log(const std::string& line) {
    std::lock_guard<std::mutex> lock(logMutex);
    if (logHandler()) logHandler()(line);
}

}  // namespace core
}  // namespace facetrack
