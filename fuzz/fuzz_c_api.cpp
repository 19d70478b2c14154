// libFuzzer target: the C API (facetrack.h) called with arbitrary arguments,
// in arbitrary order, on one tracker that lives across inputs (docs/robustness.md).
// What a C caller can get wrong is fuzzed too: NULL handles and pointers,
// negative sizes and strides, unknown pixel formats, NaN and backwards times,
// struct_size fields of older or newer callers (each struct is allocated with
// exactly the size it claims, so a write past it is an ASan report), face
// indices out of range, a tracker created from a fuzzed configuration.
//
// Input: a 32-byte header, then the pixels.
//   [0]      the call (modulo 10): process, face, reset, reset identity,
//            calibrate neutral, reset neutral, estimated shapes, create a
//            tracker from a fuzzed configuration and process one frame with it,
//            a calibration profile's JSON (the bytes after the header as text),
//            one shape's calibration (index [15], values [16..31] as four floats)
//   [1]      flags: bit 0 NULL tracker, bit 1 NULL result or face, bit 2 NULL pixels
//   [2..3]   struct_size's offset from the struct's own size (int16)
//   [4..7]   width (int32), [8..11] height (int32; cut to the rows the bytes hold)
//   [12..13] stride's offset from width x bytes per pixel (int16), [14] format (int8)
//   [15]     face index (int8), [16..23] time in seconds (the double's bits)
//   [24..31] the configuration for call 7: max faces, landmark starts,
//            calibration frames (int8 each), fov (uint8, degrees), focal
//            (uint8 x 10 px), filter flag, min cutoff and beta (uint8 / 10)
// A call must return FT_OK, FT_ERROR or FT_INVALID_ARGUMENT; after FT_OK every
// number written must be finite, and the last error a string.

#include "fuzz_common.hpp"

#include "facetrack/facetrack.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

using facetrack::fuzz::require;

template <class T>
T read(const std::uint8_t* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

/// The shipped models, loaded once (loading them per input would be most of the run).
ft_models* models() {
    static ft_models* m = [] {
        ft_models* loaded = nullptr;
        char error[256];
        require(ft_models_load_default(&loaded, error, sizeof error) == FT_OK, "the shipped models do not load");
        return loaded;
    }();
    return m;
}

ft_tracker* tracker() {
    static ft_tracker* t = [] {
        ft_tracker* created = nullptr;
        char error[256];
        require(ft_tracker_create(models(), nullptr, &created, error, sizeof error) == FT_OK, "a default tracker is not created");
        return created;
    }();
    return t;
}

void requireStatus(ft_status s) { require(s == FT_OK || s == FT_ERROR || s == FT_INVALID_ARGUMENT, "a status outside the API's three"); }

void requireFinite(const float* v, std::size_t count, const char* what) {
    for (std::size_t i = 0; i < count; ++i) require(std::isfinite(v[i]), what);
}

/// A struct of `size` bytes (at least its struct_size field), zeroed, struct_size set.
template <class T>
T* allocate(std::uint32_t size) {
    size = std::max<std::uint32_t>(size, sizeof(std::uint32_t));
    auto* p = static_cast<T*>(std::calloc(1, size));
    std::memcpy(p, &size, sizeof size);
    return p;
}

std::uint32_t claimedSize(std::size_t own, std::int16_t offset) {
    return static_cast<std::uint32_t>(
        std::clamp<std::int64_t>(static_cast<std::int64_t>(own) + offset, 0, 4 * static_cast<std::int64_t>(own)));
}

/// ft_tracker_process with the header's arguments; the frames' faces are then read back.
void process(ft_tracker* t, const std::uint8_t* header, const std::uint8_t* pixels, std::size_t available) {
    const std::uint8_t flags = header[1];
    const std::int32_t width = read<std::int32_t>(header + 4), requestedHeight = read<std::int32_t>(header + 8);
    const auto format = static_cast<ft_pixel_format>(static_cast<std::int8_t>(header[14]) % 7);
    const std::int64_t bytes = format == FT_PIXEL_GRAY8 ? 1 : format == FT_PIXEL_BGRA8 || format == FT_PIXEL_RGBA8 ? 4 : 3;
    const std::int64_t stride = static_cast<std::int64_t>(width) * bytes + read<std::int16_t>(header + 12);
    // Rows the bytes hold: the library cannot see a buffer's length, so a short
    // buffer is the caller's bug, not a finding. Sizes it must refuse pass as they are.
    std::int32_t height = requestedHeight;
    const std::int64_t row = static_cast<std::int64_t>(width) * bytes;
    if (width > 0 && requestedHeight > 0 && stride >= row) {  // then stride >= row > 0
        const auto held = static_cast<std::int64_t>(available);
        const std::int64_t rows = held < row ? 0 : 1 + (held - row) / stride;
        height = static_cast<std::int32_t>(std::min<std::int64_t>(requestedHeight, rows));
    }
    ft_frame_result* result = (flags & 2) ? nullptr
                                          : allocate<ft_frame_result>(claimedSize(sizeof(ft_frame_result), read<std::int16_t>(header + 2)));
    const ft_status s = ft_tracker_process((flags & 1) ? nullptr : t, (flags & 4) ? nullptr : pixels, width, height, stride, format,
                                           read<double>(header + 16), result);
    requireStatus(s);
    if (s == FT_OK && result && result->struct_size >= sizeof(ft_frame_result)) {
        require(result->face_count >= 0, "a negative face count");
        const float camera[4] = {result->camera_fx, result->camera_fy, result->camera_cx, result->camera_cy};
        requireFinite(camera, 4, "a camera value that is not finite");
        for (std::int32_t i = 0; i < result->face_count; ++i) {
            ft_face face{};
            face.struct_size = sizeof face;
            requireStatus(ft_tracker_face(t, i, &face));
            requireFinite(face.landmarks, 2 * FT_LANDMARK_COUNT, "a landmark that is not finite");
            requireFinite(face.arkit, FT_ARKIT_COUNT, "an ARKit weight that is not finite");
            requireFinite(face.camera_from_model, 16, "a pose that is not finite");
            requireFinite(face.pupil_left, 2, "a pupil that is not finite");
            requireFinite(face.gaze_yaw_pitch_right, 2, "a gaze angle that is not finite");
        }
    }
    std::free(result);
}

/// A tracker from a fuzzed configuration (refused or made, never a crash), one frame through it.
void createAndProcess(const std::uint8_t* header, const std::uint8_t* pixels, std::size_t available) {
    ft_tracker_config* config = allocate<ft_tracker_config>(claimedSize(sizeof(ft_tracker_config), read<std::int16_t>(header + 2)));
    const std::uint32_t size = config->struct_size;
    ft_tracker_config defaults;
    ft_tracker_config_init(&defaults);
    const std::uint8_t* c = header + 24;
    defaults.max_faces = static_cast<std::int8_t>(c[0]);
    defaults.landmark_starts = static_cast<std::int8_t>(c[1]);
    defaults.calibration_frames = static_cast<std::int8_t>(c[2]);
    defaults.horizontal_fov_deg = c[3];
    defaults.focal_length_px = 10.f * c[4];
    defaults.filter_enabled = c[5] & 1;
    defaults.filter_min_cutoff_hz = c[6] / 10.f;
    defaults.filter_beta = c[7] / 10.f - 1.f;
    std::memcpy(config, &defaults, std::min<std::size_t>(size, sizeof defaults));
    config->struct_size = size;
    char error[64];  // short: a long message must be cut, NUL-terminated
    ft_tracker* t = nullptr;
    const ft_status s = ft_tracker_create((header[1] & 1) ? nullptr : models(), config, &t, error, sizeof error);
    requireStatus(s);
    require(std::memchr(error, 0, sizeof error) != nullptr, "an error message without its NUL");
    require((s == FT_OK) == (t != nullptr), "a tracker handle that does not match the status");
    if (t) process(t, header, pixels, available);
    ft_tracker_destroy(t);
    std::free(config);
}

/// A profile's JSON from the fuzzer: refused, or taken and read back as JSON that is taken again.
void setCalibrationJson(ft_tracker* t, const std::uint8_t* text, std::size_t size) {
    std::string json(reinterpret_cast<const char*>(text), size);  // NUL-terminated, whatever the bytes hold
    const ft_status s = ft_tracker_set_calibration_json(t, json.c_str());
    requireStatus(s);
    if (s != FT_OK) return;
    std::uint32_t needed = 0;
    require(ft_tracker_calibration_json(t, nullptr, 0, &needed) == FT_INVALID_ARGUMENT && needed > 0, "no size for the JSON");
    std::string back(needed, '\0');
    require(ft_tracker_calibration_json(t, back.data(), needed, nullptr) == FT_OK, "a calibration taken is not written back");
    require(ft_tracker_set_calibration_json(t, back.c_str()) == FT_OK, "a calibration written back is refused");
}

/// One shape's calibration from the fuzzer (the header's floats): refused, or taken and read back in range.
void setShapeCalibration(ft_tracker* t, const std::uint8_t* header) {
    ft_shape_calibration* shape = (header[1] & 2) ? nullptr
                                                  : allocate<ft_shape_calibration>(
                                                        claimedSize(sizeof(ft_shape_calibration), read<std::int16_t>(header + 2)));
    if (shape) {
        const std::uint32_t size = shape->struct_size;
        ft_shape_calibration given{};
        given.struct_size = size;
        given.neutral = read<float>(header + 16), given.full = read<float>(header + 20);
        given.gain = read<float>(header + 24), given.dead_zone = read<float>(header + 28);
        std::memcpy(static_cast<void*>(shape), &given, std::min<std::size_t>(size, sizeof given));
    }
    const auto index = static_cast<std::int8_t>(header[15]);
    requireStatus(ft_tracker_set_shape_calibration(t, index, shape));
    ft_shape_calibration back{};
    back.struct_size = sizeof back;
    if (t && ft_tracker_shape_calibration(t, index, &back) == FT_OK) {
        require(back.neutral >= 0.f && back.neutral < back.full && back.full <= 1.f, "a shape's calibration out of range");
        require(back.gain > 0.f && back.gain <= 10.f && back.dead_zone >= 0.f && back.dead_zone < 1.f, "a gain or dead zone out of range");
    }
    std::free(shape);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    constexpr std::size_t kHeader = 32;
    if (size < kHeader) return 0;
    const std::uint8_t* pixels = size > kHeader ? data + kHeader : nullptr;
    const std::size_t available = size - kHeader;
    ft_tracker* t = (data[1] & 1) ? nullptr : tracker();
    switch (data[0] % 10) {
        case 0:
            process(tracker(), data, pixels, available);
            break;
        case 1: {
            ft_face* face = (data[1] & 2) ? nullptr : allocate<ft_face>(claimedSize(sizeof(ft_face), read<std::int16_t>(data + 2)));
            const ft_status s = ft_tracker_face(t, static_cast<std::int8_t>(data[15]), face);
            requireStatus(s);
            if (s == FT_OK && face && face->struct_size >= sizeof(ft_face))
                requireFinite(face->landmarks, 2 * FT_LANDMARK_COUNT, "a landmark that is not finite");
            std::free(face);
            break;
        }
        case 2:
            requireStatus(ft_tracker_reset(t));
            break;
        case 3:
            requireStatus(ft_tracker_reset_identity(t));
            break;
        case 4:
            requireStatus(ft_tracker_calibrate_neutral(t));
            break;
        case 5:
            requireStatus(ft_tracker_reset_neutral(t));
            break;
        case 6: {
            std::int32_t estimated[FT_ARKIT_COUNT];
            requireStatus(ft_tracker_estimated_shapes(t, (data[1] & 2) ? nullptr : estimated));
            break;
        }
        case 7:
            createAndProcess(data, pixels, available);
            break;
        case 8:
            if (t) setCalibrationJson(t, data + kHeader, available);
            break;
        default:
            setShapeCalibration(t, data);
            break;
    }
    const char* error = ft_tracker_last_error(t);
    require(error != nullptr, "ft_tracker_last_error gave NULL");
    require(std::strlen(error) < 4096, "a last error longer than any message");
    return 0;
}
