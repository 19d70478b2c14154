#pragma once
/// \file
/// The one error type of facetrack. Every public function that can fail throws
/// facetrack::Error; nothing else escapes the API (std::bad_alloc aside). A
/// frame with no face in it is not an error: it gives an empty result.
/// An Error owns its message; it may be copied and rethrown on any thread.

#include <stdexcept>
#include <string>

namespace facetrack {

class Error : public std::runtime_error {
public:
    explicit Error(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace facetrack
