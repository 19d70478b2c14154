#include "commands.hpp"
#include "json.hpp"
#include "media.hpp"

#include "core/environment.hpp"
#include "core/image.hpp"
#include "facetrack/facetrack.hpp"

#include <chrono>
#include <fstream>
#include <iostream>

namespace facetrack::cli {

namespace {

const char* kUsage = R"(usage: facetrack track [CLIP|DIR|IMAGE | --camera /dev/videoN] [--out results.jsonl] [--frames N]
                       [--max-faces N] [--detector auto|yunet|cascade] [--yunet PATH]
Runs the tracker and writes one JSON line per frame (to stdout, or --out):
  {"frame": N, "time_s": t, "faces": [{"tracked": b, "confidence": c, "box": [x0,y0,x1,y1],
    "landmarks": ..., "pose": ..., "blendshapes": ..., "gaze": ...}], "timings_ms": {"detect": ms, ...}}
A field whose stage is not available in this build is null ('facetrack info' lists the stages).
With no input: the first webcam, else a clip from ../shared/data/clips.)";

Json vec3(const Vec3& v) { return {v.x, v.y, v.z}; }

Json faceJson(const FaceResult& face) {
    Json j = {{"tracked", face.tracked},
                        {"confidence", round2(face.confidence)},
                        {"box", boxJson(face.box)},
                        {"landmarks", nullptr},
                        {"pose", nullptr},
                        {"blendshapes", nullptr},
                        {"gaze", nullptr}};
    if (face.landmarks) {
        j["landmarks"] = landmarksJson(*face.landmarks);
    }
    if (face.pose) {
        const auto& q = face.pose->rotation;
        j["pose"] = {{"quaternion", {q.w, q.x, q.y, q.z}},
                     {"euler_deg", vec3(face.pose->euler_deg)},
                     {"translation_mm", vec3(face.pose->translation_mm)}};
    }
    if (face.expression) {
        j["blendshapes"] = Json::object();
        for (int k = 0; k < kArkitBlendshapeCount; ++k) {
            j["blendshapes"][std::string(arkitNames()[k])] = face.expression->arkit[k];
        }
    }
    if (face.gaze) {
        auto eye = [](const EyeGaze& e) {
            return Json{{"direction", vec3(e.direction)}, {"yaw_deg", e.yaw_deg},
                                  {"pitch_deg", e.pitch_deg}, {"openness", e.openness}};
        };
        j["gaze"] = {{"left", eye(face.gaze->left)}, {"right", eye(face.gaze->right)}};
    }
    return j;
}

/// The input named on the command line, else a webcam, else a shared clip.
MediaReader openInput(const Args& args, std::string& name) {
    if (!args.positional().empty()) {
        if (args.positional().size() > 1 || args.has("--camera")) throw Error("give one input (see --help)");
        name = args.positional()[0];
        return MediaReader::open(name);
    }
    if (args.has("--camera")) {
        name = args.get("--camera");
        return MediaReader::openCamera(name);
    }
    const auto cameras = listCameras();
    if (!cameras.empty()) {
        name = cameras.front();
        return MediaReader::openCamera(name);
    }
    const std::string shared = core::sharedDirectory();
    if (!shared.empty()) {
        const auto clip = core::firstExistingFile({shared + "/data/clips/fgnet_talking_face_franck.mp4"});
        if (!clip.empty()) {
            name = clip;
            return MediaReader::open(clip);
        }
    }
    throw Error("no input: no webcam (/dev/video*) and no ../shared/data/clips. "
                "Pass a clip ('facetrack track my_clip.mp4') or a camera ('--camera /dev/video0').");
}

}  // namespace

int runTrack(const std::vector<std::string>& argv) {
    auto valued = kDetectorOptions;
    valued.insert({"--camera", "--out", "--frames", "--max-faces"});
    const Args args(argv, valued, {"--help"});
    if (args.has("--help")) {
        std::puts(kUsage);
        return 0;
    }
    const double maxFrames = args.number("--frames", -1);
    TrackerConfig config;
    config.detector = detectorConfig(args);
    config.max_faces = static_cast<int>(args.number("--max-faces", 1));

    std::string inputName;
    auto reader = openInput(args, inputName);
    Tracker tracker(Models::loadDefault(), config);
    std::cerr << "facetrack: tracking " << inputName << '\n';

    std::ofstream file;
    if (args.has("--out")) {
        file.open(args.get("--out"));
        if (!file) throw Error("cannot write '" + args.get("--out") + "'");
    }
    std::ostream& out = args.has("--out") ? file : std::cout;

    MediaFrame frame;
    int frames = 0, withFace = 0;
    const auto start = std::chrono::steady_clock::now();
    while ((maxFrames < 0 || frames < maxFrames) && reader.next(frame)) {
        const FrameResult result = tracker.process(core::viewOf(frame.bgr), frame.time_s);
        Json faces = Json::array();
        for (const auto& face : result.faces) faces.push_back(faceJson(face));
        Json timings = Json::object();
        for (const auto& t : result.timings) timings[t.stage] = round2(t.ms);
        out << Json{{"frame", frames}, {"time_s", round2(frame.time_s)}, {"faces", faces},
                              {"timings_ms", timings}}
                   .dump()
            << '\n';
        ++frames;
        withFace += result.faces.empty() ? 0 : 1;
    }
    const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
    std::cerr << "facetrack: " << frames << " frames, a face in " << withFace << ", "
              << (elapsed.count() > 0 ? frames / elapsed.count() : 0.0) << " fps (decoding included)\n";
    return 0;
}

}  // namespace facetrack::cli
