#pragma once
// The CPU time this process has used, user and system, for the "CPU, share
// of one core" figures of `facetrack send` and the app.

#include <sys/resource.h>

namespace facetrack::tools {

inline double processCpuSeconds() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
           1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

}  // namespace facetrack::tools
