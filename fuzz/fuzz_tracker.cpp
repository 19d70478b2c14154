// libFuzzer target: Tracker::process on arbitrary bytes as frames of arbitrary
// size, stride, pixel format and time stamp (docs/robustness.md). One tracker
// lives across inputs, so a stream of inputs is a stream of frames whose size,
// format and content change at every frame, with faces found and lost.
//
// Input: a 10-byte header, then the pixels.
//   width, height: uint16 little-endian (each taken modulo 1024)
//   format: uint8 (modulo 6: the five formats and one that is not a format)
//   stride padding: uint8 (bytes added to width x bytes per pixel; 255: a
//     stride one byte short of the row, which must be refused)
//   time: uint16 (milliseconds), then a flags byte: bit 0 the time is NaN,
//     bit 1 it goes back by the value instead, bit 2 the tracker is reset,
//     bit 3 the frame comes with a caller's face box (the header's last byte
//     is then its size in percent of the frame), bit 4 the frame goes to a
//     second tracker that also runs the cnn stage (none is shipped: a cascade
//     of the tests' fixture nets, random weights, two rounds of a pose and
//     expression update, then the landmark net, so that the warp and the nets
//     see every frame the shipped stages see)
// The height is cut to the rows the bytes hold: the library cannot see a
// buffer's length, so a short buffer is the caller's bug, not a finding.
// A frame must give a result or a facetrack::Error; a result's numbers must be
// finite (fuzz_common.hpp).

#include "fuzz_common.hpp"

#include "core/binary_io.hpp"
#include "facetrack/cnn_model.hpp"
#include "facetrack/error.hpp"
#include "facetrack/tracker.hpp"
#include "nn/cnn_model_data.hpp"

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <vector>

namespace {

using namespace facetrack;

Tracker& tracker() {
    static Tracker t(Models::loadDefault());
    return t;
}

Tracker& cnnTracker() {
    static const std::unique_ptr<Tracker> t = [] {
        const std::string fixtures = std::string(FACETRACK_FUZZ_SOURCE_DIR) + "/tests/data/";
        nn::CnnModelData cascade;
        cascade.expressions = {"jawOpen"};
        cascade.stages.push_back({2, core::readFileBytes(fixtures + "cnn_parity.onnx", "fixture")});
        cascade.landmark_net = core::readFileBytes(fixtures + "cnn_landmarks_fixture.onnx", "fixture");
        cascade.provenance = "fuzz_tracker: the tests' fixture nets";
        const std::string path = (std::filesystem::temp_directory_path() / "facetrack_fuzz_cascade.ftm").string();
        nn::writeCnnModel(path, cascade);
        Models models = Models::loadDefault();
        models.cnn = CnnModel::load(path);
        return std::make_unique<Tracker>(models);
    }();
    return *t;
}

std::uint16_t u16(const std::uint8_t* p) { return static_cast<std::uint16_t>(p[0] | (p[1] << 8)); }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    constexpr std::size_t kHeader = 10;
    if (size < kHeader) return 0;
    static double time = 0.0;
    const int width = u16(data) % 1024, requestedHeight = u16(data + 2) % 1024;
    const int formatIndex = data[4] % 6;
    const std::uint8_t padding = data[5];
    const std::uint16_t ms = u16(data + 6);
    const std::uint8_t flags = data[8], boxPercent = data[9];

    ImageView view;
    view.data = data + kHeader;
    view.width = width;
    view.format = static_cast<PixelFormat>(formatIndex);
    const std::size_t pixelBytes = formatIndex < 5 ? bytesPerPixel(view.format) : 3;
    const std::size_t row = static_cast<std::size_t>(width) * pixelBytes;
    view.stride = padding == 255 ? (row > 0 ? row - 1 : 0) : row + padding;
    const std::size_t available = size - kHeader;
    // Rows the bytes hold: the last row needs only `row` bytes, not a whole stride.
    const int rows = view.stride == 0 || available < row
                         ? 0
                         : static_cast<int>(std::min<std::size_t>(1 + (available - row) / view.stride, 1024));
    view.height = std::min(requestedHeight, rows);
    if (view.height == 0) view.data = available > 0 ? view.data : nullptr;

    Tracker& chosen = (flags & 16) ? cnnTracker() : tracker();
    if (flags & 4) chosen.reset();
    if (flags & 1) {
        time = std::numeric_limits<double>::quiet_NaN();
    } else {
        time = (std::isnan(time) ? 0.0 : time) + ((flags & 2) ? -1.0 : 1.0) * ms / 1000.0;
    }
    std::vector<Box> boxes;
    if (flags & 8) {
        const float s = static_cast<float>(boxPercent) / 100.f;
        boxes.push_back({0.1f * static_cast<float>(width), 0.1f * static_cast<float>(view.height), s * static_cast<float>(width),
                         s * static_cast<float>(view.height)});
    }
    FrameResult result;
    try {
        if (flags & 8) {
            chosen.process(view, time, boxes, result);
        } else {
            chosen.process(view, time, result);
        }
    } catch (const Error&) {
        return 0;  // a frame the tracker refuses, with its reason
    }
    for (const FaceResult& f : result.faces) fuzz::requireFinite(f);
    return 0;
}
