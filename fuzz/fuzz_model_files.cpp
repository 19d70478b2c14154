// libFuzzer target: every model loader on arbitrary bytes (docs/robustness.md).
//
// Input: one selector byte, then the bytes. The selector's low five bits pick
// the loader; its top bit says whether the bytes are a whole file (the
// container's header and checksum are what gets fuzzed) or a payload that the
// target wraps in a valid container (the parser behind the checksum: random
// bytes almost never pass a checksum, so without this the parsers would go
// untested), of the current version or, by bits 5-6, up to three older ones.
// A loader must load or throw facetrack::Error; any other exception escapes
// and is a finding, as is a crash or a sanitizer report.

#include "core/binary_io.hpp"
#include "gaze/eye_model_data.hpp"
#include "landmarks/lbf_model.hpp"
#include "model/face_model_data.hpp"
#include "model/landmark_convention.hpp"
#include "nn/cnn_model_data.hpp"
#include "nn/refiner_model_data.hpp"

#include "facetrack/cnn_model.hpp"
#include "facetrack/error.hpp"
#include "facetrack/eye_model.hpp"
#include "facetrack/face_model.hpp"
#include "facetrack/refiner_model.hpp"
#include "facetrack/landmark_model.hpp"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace {

using namespace facetrack;

struct Format {
    const char* magic;
    std::uint32_t version;
    void (*load)(const std::string& path);
};

const Format kFormats[] = {
    {model::kFaceModelMagic, model::kFaceModelVersion, [](const std::string& p) { FaceModel::load(p); }},
    {landmarks::kLbfMagic, landmarks::kLbfVersion, [](const std::string& p) { LandmarkModel::load(p); }},
    {gaze::kEyeModelMagic, gaze::kEyeModelVersion, [](const std::string& p) { EyeModel::load(p); }},
    {model::kConventionMagic, model::kConventionVersion, [](const std::string& p) { model::readLandmarkConvention(p); }},
    {nn::kCnnModelMagic, nn::kCnnModelVersion, [](const std::string& p) { CnnModel::load(p); }},
    {nn::kRefinerModelMagic, nn::kRefinerModelVersion, [](const std::string& p) { RefinerModel::load(p); }},
};
constexpr int kFormatCount = sizeof kFormats / sizeof kFormats[0];

const std::string& scratchPath() {
    static const std::string path = (std::filesystem::temp_directory_path() / ("facetrack_fuzz_" + std::to_string(::getpid()) + ".ftm"))
                                        .string();
    return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    const Format& format = kFormats[(data[0] & 0x1f) % kFormatCount];
    const std::uint32_t olderBy = (data[0] >> 5) & 3u;
    const std::uint32_t version = format.version > olderBy ? format.version - olderBy : 1u;
    const std::string bytes(reinterpret_cast<const char*>(data + 1), size - 1);
    const std::string& path = scratchPath();
    try {
        if (data[0] & 0x80) {
            core::writeModelFile(path, format.magic, version, bytes);
        } else {
            std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        }
        format.load(path);
    } catch (const Error&) {
        // The clear error a damaged file must give.
    }
    return 0;
}
