/* facetrack's C API (C99): the Tracker for engines and languages that call C.
 *
 *     ft_models* models = NULL;
 *     char error[256];
 *     if (ft_models_load_default(&models, error, sizeof error) != FT_OK) { puts(error); return 1; }
 *     ft_tracker_config config;
 *     ft_tracker_config_init(&config);
 *     ft_tracker* tracker = NULL;
 *     ft_tracker_create(models, &config, &tracker, error, sizeof error);
 *     ft_frame_result frame;  frame.struct_size = sizeof frame;
 *     ft_face face;           face.struct_size = sizeof face;
 *     ft_tracker_process(tracker, pixels, width, height, stride, FT_PIXEL_BGR8, time_s, &frame);
 *     for (int32_t i = 0; i < frame.face_count; ++i) ft_tracker_face(tracker, i, &face);
 *     ft_tracker_destroy(tracker);
 *     ft_models_destroy(models);
 *
 * Conventions (as ONNX Runtime's and libjpeg-turbo's tj3 C APIs):
 * - Opaque handles; every destroy function accepts NULL.
 * - Fixed-width types only. Every config and result struct starts with
 *   `struct_size`, which the caller sets to sizeof(the struct it was compiled
 *   with): a newer library fills only the fields an older caller knows.
 * - Every function returns an ft_status; no exception crosses the boundary.
 *   Creation errors are written into the caller's buffer (may be NULL); a
 *   tracker's errors are kept in the tracker (ft_tracker_last_error).
 * - Units and frames as in the C++ API (docs/api.md): millimetres, OpenCV's
 *   camera frame, the ARKit-52 order of arkitNames(), the subject's left eye
 *   first.
 * - Threads: a models handle is immutable and may be shared by trackers on
 *   any threads; a tracker is used by one thread at a time.
 * Link: the static library (facetrack::facetrack, needs the C++ runtime) or
 * the shared libfacetrack_c.so. */
#ifndef FACETRACK_FACETRACK_H
#define FACETRACK_FACETRACK_H

#include <stddef.h>
#include <stdint.h>

#if defined(_WIN32)
#define FT_API __declspec(dllexport)
#elif defined(__GNUC__)
#define FT_API __attribute__((visibility("default")))
#else
#define FT_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/** The ABI this header describes; ft_abi_version() is the library's. */
#define FT_ABI_VERSION 1

typedef int32_t ft_status;
#define FT_OK 0
#define FT_ERROR 1            /* the operation failed: see the error string */
#define FT_INVALID_ARGUMENT 2 /* a NULL handle or pointer, a bad size or index */

typedef int32_t ft_pixel_format;
#define FT_PIXEL_GRAY8 0
#define FT_PIXEL_BGR8 1
#define FT_PIXEL_RGB8 2
#define FT_PIXEL_BGRA8 3
#define FT_PIXEL_RGBA8 4

#define FT_LANDMARK_COUNT 68
#define FT_ARKIT_COUNT 52
#define FT_MAX_TIMINGS 16

typedef struct ft_models ft_models;
typedef struct ft_tracker ft_tracker;

typedef struct ft_tracker_config {
    uint32_t struct_size;
    int32_t max_faces;          /* faces followed at once (1) */
    float horizontal_fov_deg;   /* the webcam's field of view (60) */
    float focal_length_px;      /* > 0: use it instead of the field of view (0) */
    int32_t filter_enabled;     /* the 1-euro filter (1) */
    float filter_min_cutoff_hz; /* (1) */
    float filter_beta;          /* (2) */
    int32_t calibration_frames; /* identity from this many samples; 0: mean face (30) */
    float expression_prior;     /* factor on the fit's learned expression prior, (0, 100] (1) */
    int32_t landmark_starts;    /* landmark passes averaged, 1..9; each ~0.2 ms (3) */
    /* Added after the first release of this struct: an older caller's struct_size ends before it
       and it keeps its default. */
    int32_t cnn_stage; /* the CNN file's cascade stages: the shipped expression nets, ~0.3 ms (1) */
} ft_tracker_config;

/* How one ARKit weight is reported (the C++ ShapeCalibration, facetrack/calibration.hpp):
 * w' = min(gain r', 1), r' = r with the dead zone taken off, r = clamp((w - neutral) / (full - neutral), 0, 1). */
typedef struct ft_shape_calibration {
    uint32_t struct_size;
    float neutral;   /* the weight on the user's relaxed face, [0, 1) (0) */
    float full;      /* the weight of their full expression, (neutral, 1] (1) */
    float gain;      /* (0, 10] (1) */
    float dead_zone; /* [0, 1) (0) */
} ft_shape_calibration;

typedef struct ft_timing {
    char stage[16]; /* NUL-terminated: "detect", "landmarks", "fit", ... */
    double ms;
} ft_timing;

typedef struct ft_frame_result {
    uint32_t struct_size;
    int32_t face_count; /* read each with ft_tracker_face */
    float camera_fx, camera_fy, camera_cx, camera_cy;
    int32_t timing_count;
    ft_timing timings[FT_MAX_TIMINGS];
} ft_frame_result;

typedef struct ft_face {
    uint32_t struct_size;
    int32_t id;
    int32_t tracked; /* 1: followed from the previous frame */
    float confidence;
    float box[4]; /* x0, y0, x1, y1 pixels */
    int32_t has_landmarks;
    float landmarks[2 * FT_LANDMARK_COUNT]; /* x0, y0, x1, y1, ... pixels */
    int32_t has_pose;
    float rotation_wxyz[4]; /* x_camera = R x_model + t */
    float euler_deg[3];     /* pitch, yaw, roll */
    float translation_mm[3];
    float camera_from_model[16]; /* column-major */
    float gl_model_view[16];     /* column-major, OpenGL's eye frame */
    int32_t has_expression;
    float arkit[FT_ARKIT_COUNT];
    int32_t has_gaze;
    float gaze_left[3], gaze_right[3]; /* unit directions, camera frame */
    float openness_left, openness_right;
    int32_t has_fit_residual;
    float fit_residual;
    int32_t identity_calibrated;
    /* Added in ABI 1 after the first release of this struct: older callers'
       struct_size ends before them and they are not written. */
    float gaze_yaw_pitch_left[2], gaze_yaw_pitch_right[2]; /* degrees, head frame (docs/gaze.md) */
    float pupil_left[2], pupil_right[2];                   /* iris centres, pixels */
} ft_face;

/** The library's ABI version (compare with FT_ABI_VERSION) and version string. */
FT_API uint32_t ft_abi_version(void);
FT_API const char* ft_version_string(void);
/** The name of ARKit weight `index` (0..51), or NULL. */
FT_API const char* ft_arkit_name(int32_t index);

/** The shipped models (docs/models.md says where they are looked for). */
FT_API ft_status ft_models_load_default(ft_models** out, char* error, uint32_t error_size);
FT_API void ft_models_destroy(ft_models* models);

/** The defaults above, with struct_size set. */
FT_API void ft_tracker_config_init(ft_tracker_config* config);
/** config may be NULL (defaults). The tracker holds its own reference to the models. */
FT_API ft_status ft_tracker_create(const ft_models* models, const ft_tracker_config* config, ft_tracker** out, char* error,
                                   uint32_t error_size);
FT_API void ft_tracker_destroy(ft_tracker* tracker);

/** The next frame of the stream; time_s must increase (see the C++ API).
 *  Fills `result` (its struct_size set by the caller); the faces stay readable
 *  through ft_tracker_face until the next call. */
FT_API ft_status ft_tracker_process(ft_tracker* tracker, const uint8_t* pixels, int32_t width, int32_t height, int64_t stride,
                                    ft_pixel_format format, double time_s, ft_frame_result* result);
/** Face `index` (< face_count) of the last processed frame. */
FT_API ft_status ft_tracker_face(const ft_tracker* tracker, int32_t index, ft_face* face);
/** Forget every face (a new stream) / the calibrated identities. */
FT_API ft_status ft_tracker_reset(ft_tracker* tracker);
FT_API ft_status ft_tracker_reset_identity(ft_tracker* tracker);
/** Take the first followed face's current expression as the user's neutral
 *  (the C++ Tracker::calibrateNeutral) / set every neutral back to 0. */
FT_API ft_status ft_tracker_calibrate_neutral(ft_tracker* tracker);
FT_API ft_status ft_tracker_reset_neutral(ft_tracker* tracker);
/** The user's calibration (the C++ Tracker::calibration, setCalibration), one
 *  ARKit shape (index 0..51) at a time: `shape->struct_size` set by the caller;
 *  setting changes only that shape, and fields past the caller's struct_size keep their value. */
FT_API ft_status ft_tracker_shape_calibration(ft_tracker* tracker, int32_t index, ft_shape_calibration* shape);
FT_API ft_status ft_tracker_set_shape_calibration(ft_tracker* tracker, int32_t index, const ft_shape_calibration* shape);
/** The whole calibration as the profile's JSON text: written into `buffer`
 *  (NUL-terminated) when `size` holds it, else FT_INVALID_ARGUMENT; `needed`
 *  (may be NULL) gets the size it takes, NUL included. */
FT_API ft_status ft_tracker_calibration_json(ft_tracker* tracker, char* buffer, uint32_t size, uint32_t* needed);
FT_API ft_status ft_tracker_set_calibration_json(ft_tracker* tracker, const char* json);
/** Read / write the profile file at `path`; NULL: the user's default
 *  ($XDG_CONFIG_HOME/facetrack/profile.json). A bad file is FT_ERROR, the tracker unchanged. */
FT_API ft_status ft_tracker_load_profile(ft_tracker* tracker, const char* path);
FT_API ft_status ft_tracker_save_profile(ft_tracker* tracker, const char* path);
/** Which ARKit shapes some stage estimates (the C++ Tracker::estimatedShapes):
 *  estimated[i] = 1 for ft_arkit_name(i) when one does, 0 when it is always 0.
 *  `estimated` holds FT_ARKIT_COUNT values. */
FT_API ft_status ft_tracker_estimated_shapes(const ft_tracker* tracker, int32_t estimated[FT_ARKIT_COUNT]);
/** The tracker's last error ("" after a success); owned by the tracker, valid
 *  until its next call. NULL tracker: a static string saying so. */
FT_API const char* ft_tracker_last_error(const ft_tracker* tracker);

#ifdef __cplusplus
}
#endif

#endif /* FACETRACK_FACETRACK_H */
