#pragma once
// The main() of facetrack's tools: run, and turn any exception into one line
// on stderr and exit code 1.

#include <cstdio>
#include <exception>

namespace facetrack::tools {

inline int runTool(const char* name, int (*run)(int, char**), int argc, char** argv) {
    try {
        return run(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "\n%s: %s\n", name, e.what());
        return 1;
    }
}

}  // namespace facetrack::tools
