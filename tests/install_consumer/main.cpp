// Uses only the installed public headers: load the shipped model, run a Tracker on a blank frame.
#include <facetrack/facetrack.hpp>

#include <cstdio>
#include <vector>

int main(int argc, char** argv) {
    if (argc != 2) return 2;
    try {
        facetrack::Models models;
        models.face = facetrack::FaceModel::load(argv[1]);
        facetrack::TrackerConfig config;
        config.detector.kind = facetrack::DetectorKind::Cascade;
        facetrack::Tracker tracker(models, config);
        std::vector<std::uint8_t> gray(320 * 240, 128);
        const auto result = tracker.process({gray.data(), 320, 240, 320, facetrack::PixelFormat::Gray8}, 0.0);
        std::printf("facetrack %s: %d vertices, %zu faces in a blank frame\n", facetrack::versionString(), models.face->vertexCount(),
                    result.faces.size());
        return result.faces.empty() ? 0 : 1;
    } catch (const facetrack::Error& e) {
        std::fprintf(stderr, "consumer: %s\n", e.what());
        return 1;
    }
}
