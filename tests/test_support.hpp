#pragma once
// Helpers shared by the tests: where ../shared is, and skipping without it.

#include "core/environment.hpp"

#include <gtest/gtest.h>

#include <string>

namespace facetrack::test {

inline std::string sharedDir() { return core::sharedDirectory(); }

/// Skips the calling test, with a message saying why, when ../shared is absent.
#define FACETRACK_REQUIRE_SHARED()                                                              \
    do {                                                                                        \
        if (::facetrack::test::sharedDir().empty())                                             \
            GTEST_SKIP() << "../shared not found (set FACETRACK_SHARED_DIR); this test needs it"; \
    } while (0)

inline std::string sourceDir() { return FACETRACK_TEST_SOURCE_DIR; }
inline std::string shippedFaceModel() { return sourceDir() + "/models/face_model.ftm"; }

}  // namespace facetrack::test
