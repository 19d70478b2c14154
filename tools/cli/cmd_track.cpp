#include "app/media.hpp"
#include "app/overlay.hpp"
#include "commands.hpp"
#include "json.hpp"

#include "app/image_view.hpp"
#include "core/environment.hpp"
#include "facetrack/facetrack.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>

namespace facetrack::cli {

namespace {

const char* kUsage = R"(usage: facetrack track [CLIP|DIR|IMAGE | --camera /dev/videoN] [--out results.jsonl] [--overlay out.mp4]
                       [--frames N] [--raw] [--neutral-at SECONDS] [--profile FILE|none] [tracker options]
Runs the tracker and writes one JSON line per frame (to stdout, or --out):
  {"frame": N, "time_s": t, "tracked": b, "id": i, "detected": b, "confidence": c, "fit_residual": r,
   "box": [x0,y0,x1,y1], "landmarks": [[x,y] x 68], "pose": {"quaternion": [w,x,y,z],
   "euler_deg": [pitch,yaw,roll], "translation_mm": [x,y,z]}, "blendshapes": {52 ARKit names: w},
   "gaze": ..., "identity_calibrated": b, "timings_ms": {"detect": ms, "landmarks": ms, ...}}
--profile FILE applies a calibration profile ('facetrack calibrate' writes one); without it the
user's default profile ($XDG_CONFIG_HOME/facetrack/profile.json) when there is one; none: no
calibration. --neutral-at S takes the face's expression at S seconds as its neutral
(Tracker::calibrateNeutral): the weights after it are measured from there.
"tracked" says whether a face was followed in this frame; the face fields are the first face's
(null without a face, or when their stage is not available: 'facetrack info' lists the stages).
With --max-faces N > 1 a "faces" array holds every face. --raw adds "raw": the values before
temporal filtering. docs/api.md gives the axis conventions.
--overlay writes a video with the mesh wireframe, landmarks and head axes drawn in.
Tracker options: --max-faces N, --fov DEG (default 60), --focal PX, --calibration-frames N (0: mean face),
  --expression-prior F (factor on the fit's learned expression prior, default 1; below 1 expressions
  respond more), --landmark-starts N (landmark passes averaged, 1..9, default 3), --no-filter,
  --filter-cutoff HZ, --filter-beta B, --refiner FILE|none (landmark refiner), --cnn FILE|none (CNN file),
  --no-cnn-stage (no expressions read from the texture, ~0.3 ms less a frame), --eyes FILE|none (eye model),
  and the detector options.
With no input: the first webcam, else a clip from ../shared/data/clips.)";

Json vec3(const Vec3& v) { return {v.x, v.y, v.z}; }

Json poseJson(const std::optional<HeadPose>& pose) {
    if (!pose) return nullptr;
    const auto& q = pose->rotation;
    return {{"quaternion", {q.w, q.x, q.y, q.z}}, {"euler_deg", vec3(pose->euler_deg)}, {"translation_mm", vec3(pose->translation_mm)}};
}

Json blendshapesJson(const std::optional<ExpressionResult>& expression) {
    if (!expression) return nullptr;
    Json out = Json::object();
    for (int k = 0; k < kArkitBlendshapeCount; ++k) out[std::string(arkitNames()[k])] = round2(expression->arkit[k]);
    return out;
}

Json landmarksOrNull(const std::optional<Landmarks68>& landmarks) { return landmarks ? landmarksJson(*landmarks) : Json(nullptr); }

Json faceJson(const FaceResult& face, bool raw) {
    Json j = {{"id", face.id},
              {"detected", !face.tracked},
              {"confidence", round2(face.confidence)},
              {"fit_residual", face.fit_residual ? Json(std::round(*face.fit_residual * 1e4) / 1e4) : Json(nullptr)},
              {"box", boxJson(face.box)},
              {"landmarks", landmarksOrNull(face.landmarks)},
              {"pose", poseJson(face.pose)},
              {"blendshapes", blendshapesJson(face.expression)},
              {"gaze", nullptr},
              {"identity_calibrated", face.identity_calibrated}};
    if (face.gaze) {
        auto eye = [](const EyeGaze& e) {
            return Json{{"vector", vec3(e.direction)},    {"vector_head", vec3(e.direction_head)},
                        {"yaw_deg", round2(e.yaw_deg)},   {"pitch_deg", round2(e.pitch_deg)},
                        {"openness", round2(e.openness)}, {"pupil", {round2(e.pupil_px.x), round2(e.pupil_px.y)}}};
        };
        j["gaze"] = {{"left", eye(face.gaze->left)}, {"right", eye(face.gaze->right)}};
    }
    if (raw) {
        // With the filter off (no raw values) the fields themselves are the unfiltered ones.
        const bool filtered = face.raw.landmarks || face.raw.pose || face.raw.expression;
        j["raw"] = {{"landmarks", landmarksOrNull(filtered ? face.raw.landmarks : face.landmarks)},
                    {"pose", poseJson(filtered ? face.raw.pose : face.pose)},
                    {"blendshapes", blendshapesJson(filtered ? face.raw.expression : face.expression)}};
    }
    return j;
}

/// One output line: the frame, the first face's fields at the top level, every face under
/// "faces" when several may be followed.
Json frameJson(int frame, double time_s, const FrameResult& result, int maxFaces, bool raw) {
    Json j = {{"frame", frame}, {"time_s", std::round(time_s * 1e4) / 1e4}, {"tracked", !result.faces.empty()}};
    const Json first = result.faces.empty() ? faceJson(FaceResult{}, raw) : faceJson(result.faces.front(), raw);
    for (const auto& [key, value] : first.items()) {
        j[key] = result.faces.empty() ? Json(nullptr) : value;
    }
    if (maxFaces > 1) {
        j["faces"] = Json::array();
        for (const auto& face : result.faces) j["faces"].push_back(faceJson(face, raw));
    }
    Json timings = Json::object();
    for (const auto& t : result.timings) timings[t.stage] = std::round(t.ms * 1e3) / 1e3;
    j["timings_ms"] = timings;
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
        return MediaReader::openCamera({name});
    }
    const auto cameras = CameraCapture::listDevices();
    if (!cameras.empty()) {
        name = cameras.front();
        return MediaReader::openCamera({name});
    }
    const std::string shared = core::sharedDirectory();
    if (!shared.empty()) {
        const auto clip = core::firstExistingFile({shared + "/data/clips/fgnet_talking_face_franck.mp4"});
        if (!clip.empty()) {
            name = clip;
            return MediaReader::open(clip);
        }
    }
    throw Error(
        "no input: no webcam (/dev/video*) and no ../shared/data/clips. "
        "Pass a clip ('facetrack track my_clip.mp4') or a camera ('--camera /dev/video0').");
}

}  // namespace

int runTrack(const std::vector<std::string>& argv) {
    const Args args(argv, trackingOptions({"--camera", "--out", "--frames", "--overlay", "--neutral-at", "--profile"}),
                    trackingFlags({"--help", "--raw"}));
    if (args.has("--help")) {
        std::puts(kUsage);
        return 0;
    }
    const int maxFrames = args.integer("--frames", -1);
    // --neutral-at S: Tracker::calibrateNeutral() after the first frame at or past S seconds.
    const double neutralAt = args.number("--neutral-at", -1.0);
    if (args.has("--neutral-at") && !(neutralAt >= 0.0 && neutralAt < 1e9)) throw Error("--neutral-at must be seconds, 0 or more");
    const bool raw = args.has("--raw");
    const TrackerConfig config = trackerConfig(args);
    Tracker tracker(trackingModels(args), config);
    tracker.setCalibration(tools::userCalibration(args));

    std::string inputName;
    auto reader = openInput(args, inputName);
    std::cerr << "facetrack: tracking " << inputName << '\n';

    std::ofstream file;
    if (args.has("--out")) {
        file.open(args.get("--out"));
        if (!file) throw Error("cannot write '" + args.get("--out") + "'");
    }
    std::ostream& out = args.has("--out") ? file : std::cout;
    OverlayRenderer overlay(tracker.models().face);
    cv::VideoWriter video;
    cv::Size videoSize;

    bool neutralDone = neutralAt < 0;
    MediaFrame frame;
    int frames = 0, withFace = 0;
    double trackerSeconds = 0.0;
    while ((maxFrames < 0 || frames < maxFrames) && reader.next(frame)) {
        const auto start = std::chrono::steady_clock::now();
        if (reader.isStillImages()) tracker.reset();  // unrelated photos: nothing to follow
        const FrameResult result = tracker.process(tools::viewOf(frame.bgr), frame.time_s);
        if (!neutralDone && frame.time_s >= neutralAt) {
            tracker.calibrateNeutral();
            neutralDone = true;
        }
        trackerSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        out << frameJson(frames, frame.time_s, result, config.max_faces, raw).dump() << '\n';
        if (args.has("--overlay")) {
            if (!video.isOpened()) {
                const double fps = reader.fps() > 0 ? reader.fps() : 30.0;
                videoSize = frame.bgr.size();
                video.open(args.get("--overlay"), cv::VideoWriter::fourcc('m', 'p', '4', 'v'), fps, videoSize);
                if (!video.isOpened()) throw Error("cannot write video '" + args.get("--overlay") + "'");
            }
            cv::Mat canvas = frame.bgr.clone();
            overlay.draw(canvas, result);
            if (canvas.size() != videoSize) cv::resize(canvas, canvas, videoSize);  // images of a folder may differ
            video.write(canvas);
        }
        ++frames;
        withFace += result.faces.empty() ? 0 : 1;
    }
    std::cerr << "facetrack: " << frames << " frames, a face in " << withFace << ", tracker "
              << (trackerSeconds > 0 ? frames / trackerSeconds : 0.0) << " fps (decoding and output excluded)\n";
    return 0;
}

}  // namespace facetrack::cli
