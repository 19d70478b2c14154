// The C API (facetrack/facetrack.h) over the C++ one. Every exported function
// catches everything: no exception crosses into C.

#include "facetrack/facetrack.h"

#include "facetrack/facetrack.hpp"

#include <algorithm>
#include <cstring>
#include <exception>
#include <string>

struct ft_models {
    facetrack::Models models;
};

struct ft_tracker {
    facetrack::Tracker tracker;
    facetrack::FrameResult last;  // reused frame to frame
    std::string error;
};

namespace {

void writeError(char* buffer, uint32_t size, const std::string& message) {
    if (!buffer || size == 0) return;
    const std::size_t n = std::min<std::size_t>(message.size(), size - 1);
    std::memcpy(buffer, message.data(), n);
    buffer[n] = '\0';
}

/// Runs `body`, turning any exception into FT_ERROR and a message.
template <class Body>
ft_status guarded(std::string& error, Body&& body) {
    try {
        error.clear();
        body();
        return FT_OK;
    } catch (const std::exception& e) {
        error = e.what();
    } catch (...) {
        error = "unknown error";
    }
    return FT_ERROR;
}

/// Copies `full` into the caller's struct, as much of it as the caller's
/// struct_size says it has (an older caller knows fewer fields).
template <class T>
ft_status copyOut(const T& full, T* out) {
    if (!out || out->struct_size < sizeof(uint32_t)) return FT_INVALID_ARGUMENT;
    const uint32_t size = std::min<uint32_t>(out->struct_size, sizeof(T));
    std::memcpy(static_cast<void*>(out), &full, size);
    out->struct_size = size;
    return FT_OK;
}

facetrack::PixelFormat pixelFormatOf(ft_pixel_format format) {
    switch (format) {
        case FT_PIXEL_GRAY8:
            return facetrack::PixelFormat::Gray8;
        case FT_PIXEL_BGR8:
            return facetrack::PixelFormat::Bgr8;
        case FT_PIXEL_RGB8:
            return facetrack::PixelFormat::Rgb8;
        case FT_PIXEL_BGRA8:
            return facetrack::PixelFormat::Bgra8;
        case FT_PIXEL_RGBA8:
            return facetrack::PixelFormat::Rgba8;
    }
    throw facetrack::Error("unknown pixel format " + std::to_string(format));
}

void copyVec3(const facetrack::Vec3& v, float* out) {
    out[0] = v.x;
    out[1] = v.y;
    out[2] = v.z;
}

}  // namespace

extern "C" {

uint32_t ft_abi_version(void) { return FT_ABI_VERSION; }

const char* ft_version_string(void) { return facetrack::versionString(); }

const char* ft_arkit_name(int32_t index) {
    if (index < 0 || index >= facetrack::kArkitBlendshapeCount) return nullptr;
    return facetrack::arkitNames()[index].data();  // the names are NUL-terminated literals
}

ft_status ft_models_load_default(ft_models** out, char* error, uint32_t error_size) {
    if (!out) return FT_INVALID_ARGUMENT;
    *out = nullptr;
    std::string message;
    const ft_status status = guarded(message, [&] { *out = new ft_models{facetrack::Models::loadDefault()}; });
    writeError(error, error_size, message);
    return status;
}

void ft_models_destroy(ft_models* models) { delete models; }

void ft_tracker_config_init(ft_tracker_config* config) {
    if (!config) return;
    const facetrack::TrackerConfig defaults;
    *config = ft_tracker_config{};
    config->struct_size = sizeof(ft_tracker_config);
    config->max_faces = defaults.max_faces;
    config->horizontal_fov_deg = static_cast<float>(defaults.camera.horizontal_fov_deg);
    config->focal_length_px = static_cast<float>(defaults.camera.focal_length_px);
    config->filter_enabled = defaults.filter.enabled ? 1 : 0;
    config->filter_min_cutoff_hz = static_cast<float>(defaults.filter.min_cutoff_hz);
    config->filter_beta = static_cast<float>(defaults.filter.beta);
    config->calibration_frames = defaults.calibration_frames;
    config->expression_prior = defaults.expression_prior;
    config->landmark_starts = defaults.landmark_starts;
    config->cnn_stage = defaults.cnn_stage ? 1 : 0;
}

ft_status ft_tracker_create(const ft_models* models, const ft_tracker_config* config, ft_tracker** out, char* error, uint32_t error_size) {
    if (!out) return FT_INVALID_ARGUMENT;
    *out = nullptr;
    if (!models) {
        writeError(error, error_size, "ft_tracker_create: no models");
        return FT_INVALID_ARGUMENT;
    }
    // Defaults for every field the caller's (possibly older) struct does not have.
    ft_tracker_config c;
    ft_tracker_config_init(&c);
    if (config) {
        if (config->struct_size < sizeof(uint32_t)) {
            writeError(error, error_size, "ft_tracker_create: config.struct_size is not set");
            return FT_INVALID_ARGUMENT;
        }
        std::memcpy(&c, config, std::min<std::size_t>(config->struct_size, sizeof c));
    }
    std::string message;
    const ft_status status = guarded(message, [&] {
        facetrack::TrackerConfig t;
        t.max_faces = c.max_faces;
        t.camera.horizontal_fov_deg = c.horizontal_fov_deg;
        t.camera.focal_length_px = c.focal_length_px;
        t.filter.enabled = c.filter_enabled != 0;
        t.filter.min_cutoff_hz = c.filter_min_cutoff_hz;
        t.filter.beta = c.filter_beta;
        t.calibration_frames = c.calibration_frames;
        t.expression_prior = c.expression_prior;
        t.landmark_starts = c.landmark_starts;
        t.cnn_stage = c.cnn_stage != 0;
        *out = new ft_tracker{facetrack::Tracker(models->models, t), {}, {}};
    });
    writeError(error, error_size, message);
    return status;
}

void ft_tracker_destroy(ft_tracker* tracker) { delete tracker; }

ft_status ft_tracker_process(ft_tracker* tracker, const uint8_t* pixels, int32_t width, int32_t height, int64_t stride,
                             ft_pixel_format format, double time_s, ft_frame_result* result) {
    if (!tracker) return FT_INVALID_ARGUMENT;
    if (!result || result->struct_size < sizeof(uint32_t) || stride < 0) {
        tracker->error = "ft_tracker_process: result.struct_size not set, or a negative stride";
        return FT_INVALID_ARGUMENT;
    }
    return guarded(tracker->error, [&] {
        const facetrack::ImageView view{pixels, width, height, static_cast<std::size_t>(stride), pixelFormatOf(format)};
        tracker->tracker.process(view, time_s, tracker->last);
        const facetrack::FrameResult& r = tracker->last;
        ft_frame_result full{};
        full.struct_size = sizeof full;
        full.face_count = static_cast<int32_t>(r.faces.size());
        full.camera_fx = r.camera.fx;
        full.camera_fy = r.camera.fy;
        full.camera_cx = r.camera.cx;
        full.camera_cy = r.camera.cy;
        for (const auto& t : r.timings) {
            if (full.timing_count == FT_MAX_TIMINGS) break;
            ft_timing& out = full.timings[full.timing_count++];
            std::strncpy(out.stage, t.stage.c_str(), sizeof out.stage - 1);
            out.ms = t.ms;
        }
        copyOut(full, result);
    });
}

ft_status ft_tracker_face(const ft_tracker* tracker, int32_t index, ft_face* face) {
    if (!tracker) return FT_INVALID_ARGUMENT;
    if (index < 0 || index >= static_cast<int32_t>(tracker->last.faces.size()) || !face || face->struct_size < sizeof(uint32_t)) {
        return FT_INVALID_ARGUMENT;
    }
    const facetrack::FaceResult& f = tracker->last.faces[static_cast<std::size_t>(index)];
    ft_face full{};
    full.struct_size = sizeof full;
    full.id = f.id;
    full.tracked = f.tracked ? 1 : 0;
    full.confidence = f.confidence;
    full.box[0] = f.box.x0, full.box[1] = f.box.y0, full.box[2] = f.box.x1, full.box[3] = f.box.y1;
    if (f.landmarks) {
        full.has_landmarks = 1;
        for (int i = 0; i < FT_LANDMARK_COUNT; ++i) {
            full.landmarks[2 * i] = (*f.landmarks)[i].x;
            full.landmarks[2 * i + 1] = (*f.landmarks)[i].y;
        }
    }
    if (f.pose) {
        full.has_pose = 1;
        const auto& q = f.pose->rotation;
        full.rotation_wxyz[0] = q.w, full.rotation_wxyz[1] = q.x, full.rotation_wxyz[2] = q.y, full.rotation_wxyz[3] = q.z;
        copyVec3(f.pose->euler_deg, full.euler_deg);
        copyVec3(f.pose->translation_mm, full.translation_mm);
        std::copy(f.pose->camera_from_model.begin(), f.pose->camera_from_model.end(), full.camera_from_model);
        std::copy(f.pose->gl_model_view.begin(), f.pose->gl_model_view.end(), full.gl_model_view);
    }
    if (f.expression) {
        full.has_expression = 1;
        std::copy(f.expression->arkit.begin(), f.expression->arkit.end(), full.arkit);
    }
    if (f.gaze) {
        full.has_gaze = 1;
        copyVec3(f.gaze->left.direction, full.gaze_left);
        copyVec3(f.gaze->right.direction, full.gaze_right);
        full.openness_left = f.gaze->left.openness;
        full.openness_right = f.gaze->right.openness;
        full.gaze_yaw_pitch_left[0] = f.gaze->left.yaw_deg, full.gaze_yaw_pitch_left[1] = f.gaze->left.pitch_deg;
        full.gaze_yaw_pitch_right[0] = f.gaze->right.yaw_deg, full.gaze_yaw_pitch_right[1] = f.gaze->right.pitch_deg;
        full.pupil_left[0] = f.gaze->left.pupil_px.x, full.pupil_left[1] = f.gaze->left.pupil_px.y;
        full.pupil_right[0] = f.gaze->right.pupil_px.x, full.pupil_right[1] = f.gaze->right.pupil_px.y;
    }
    if (f.fit_residual) {
        full.has_fit_residual = 1;
        full.fit_residual = *f.fit_residual;
    }
    full.identity_calibrated = f.identity_calibrated ? 1 : 0;
    return copyOut(full, face);
}

ft_status ft_tracker_reset(ft_tracker* tracker) {
    if (!tracker) return FT_INVALID_ARGUMENT;
    return guarded(tracker->error, [&] { tracker->tracker.reset(); });
}

ft_status ft_tracker_reset_identity(ft_tracker* tracker) {
    if (!tracker) return FT_INVALID_ARGUMENT;
    return guarded(tracker->error, [&] { tracker->tracker.resetIdentity(); });
}

ft_status ft_tracker_calibrate_neutral(ft_tracker* tracker) {
    if (!tracker) return FT_INVALID_ARGUMENT;
    return guarded(tracker->error, [&] { tracker->tracker.calibrateNeutral(); });
}

ft_status ft_tracker_reset_neutral(ft_tracker* tracker) {
    if (!tracker) return FT_INVALID_ARGUMENT;
    return guarded(tracker->error, [&] { tracker->tracker.resetNeutral(); });
}

ft_status ft_tracker_shape_calibration(ft_tracker* tracker, int32_t index, ft_shape_calibration* shape) {
    if (!tracker || !shape || index < 0 || index >= FT_ARKIT_COUNT) return FT_INVALID_ARGUMENT;
    const facetrack::ShapeCalibration s = tracker->tracker.calibration().shapes[static_cast<std::size_t>(index)];
    ft_shape_calibration full{sizeof(ft_shape_calibration), s.neutral, s.full, s.gain, s.dead_zone};
    return copyOut(full, shape);
}

ft_status ft_tracker_set_shape_calibration(ft_tracker* tracker, int32_t index, const ft_shape_calibration* shape) {
    if (!tracker || !shape || shape->struct_size < sizeof(uint32_t) || index < 0 || index >= FT_ARKIT_COUNT) return FT_INVALID_ARGUMENT;
    return guarded(tracker->error, [&] {
        facetrack::Calibration calibration = tracker->tracker.calibration();
        facetrack::ShapeCalibration& s = calibration.shapes[static_cast<std::size_t>(index)];
        ft_shape_calibration given{sizeof(ft_shape_calibration), s.neutral, s.full, s.gain, s.dead_zone};
        std::memcpy(static_cast<void*>(&given), shape, std::min<uint32_t>(shape->struct_size, sizeof given));
        s = {given.neutral, given.full, given.gain, given.dead_zone};
        tracker->tracker.setCalibration(calibration);
    });
}

ft_status ft_tracker_calibration_json(ft_tracker* tracker, char* buffer, uint32_t size, uint32_t* needed) {
    if (!tracker) return FT_INVALID_ARGUMENT;
    std::string json;
    const ft_status status = guarded(tracker->error, [&] { json = facetrack::toJson(tracker->tracker.calibration()); });
    if (status != FT_OK) return status;
    if (needed) *needed = static_cast<uint32_t>(json.size() + 1);
    if (!buffer || size < json.size() + 1) return FT_INVALID_ARGUMENT;
    std::memcpy(buffer, json.c_str(), json.size() + 1);
    return FT_OK;
}

ft_status ft_tracker_set_calibration_json(ft_tracker* tracker, const char* json) {
    if (!tracker || !json) return FT_INVALID_ARGUMENT;
    return guarded(tracker->error, [&] { tracker->tracker.setCalibration(facetrack::calibrationFromJson(json)); });
}

ft_status ft_tracker_load_profile(ft_tracker* tracker, const char* path) {
    if (!tracker) return FT_INVALID_ARGUMENT;
    return guarded(tracker->error,
                   [&] { tracker->tracker.setCalibration(facetrack::loadCalibration(path ? path : facetrack::defaultProfilePath())); });
}

ft_status ft_tracker_save_profile(ft_tracker* tracker, const char* path) {
    if (!tracker) return FT_INVALID_ARGUMENT;
    return guarded(tracker->error,
                   [&] { facetrack::saveCalibration(tracker->tracker.calibration(), path ? path : facetrack::defaultProfilePath()); });
}

ft_status ft_tracker_estimated_shapes(const ft_tracker* tracker, int32_t estimated[FT_ARKIT_COUNT]) {
    if (!tracker || !estimated) return FT_INVALID_ARGUMENT;
    std::string ignored;
    return guarded(ignored, [&] {
        std::fill(estimated, estimated + FT_ARKIT_COUNT, 0);
        for (const auto& name : tracker->tracker.estimatedShapes()) estimated[facetrack::arkitIndex(name)] = 1;
    });
}

const char* ft_tracker_last_error(const ft_tracker* tracker) {
    return tracker ? tracker->error.c_str() : "ft_tracker_last_error: no tracker";
}

}  // extern "C"
