#pragma once
// Shared by the libFuzzer targets (docs/robustness.md): besides a crash or a
// sanitizer report, a finding is a result with a number that is not finite.

#include "common/finite_result.hpp"

#include <cstdio>
#include <cstdlib>
#include <string>

namespace facetrack::fuzz {

/// Stops the run, naming `why`, unless `ok`.
inline void require(bool ok, const char* why) {
    if (ok) return;
    std::fprintf(stderr, "fuzz finding: %s\n", why);
    std::abort();
}

inline void requireFinite(const FaceResult& f) {
    const std::string bad = tools::firstNonFinite(f);
    require(bad.empty(), bad.c_str());
}

}  // namespace facetrack::fuzz
