// The C++ API's poses for raw BGR frames on stdin (width and height as
// arguments), one line per frame: "face qw qx qy qz tx ty tz" or "none".
// test_capi.py compares the C API, loaded from libfacetrack_c.so with ctypes, against it.

#include "facetrack/facetrack.hpp"

#include <cstdio>
#include <cstdlib>
#include <vector>

int main(int argc, char** argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: capi_reference WIDTH HEIGHT < frames.bgr\n");
        return 2;
    }
    const int width = std::atoi(argv[1]), height = std::atoi(argv[2]);
    try {
        facetrack::Tracker tracker(facetrack::Models::loadDefault());
        facetrack::FrameResult result;
        std::vector<std::uint8_t> pixels(static_cast<std::size_t>(width) * height * 3);
        for (int frame = 0; std::fread(pixels.data(), 1, pixels.size(), stdin) == pixels.size(); ++frame) {
            tracker.process({pixels.data(), width, height, static_cast<std::size_t>(width) * 3, facetrack::PixelFormat::Bgr8}, frame / 30.0,
                            result);
            if (result.faces.empty() || !result.faces[0].pose) {
                std::printf("none\n");
                continue;
            }
            const auto& p = *result.faces[0].pose;
            std::printf("face %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z,
                        p.translation_mm.x, p.translation_mm.y, p.translation_mm.z);
        }
    } catch (const facetrack::Error& e) {
        std::fprintf(stderr, "capi_reference: %s\n", e.what());
        return 1;
    }
    return 0;
}
