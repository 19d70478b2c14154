// facetrack: the command-line front end (docs/cli.md).

#include "commands.hpp"

#include <opencv2/core/utils/logger.hpp>

#include <cstdio>
#include <cstring>
#include <functional>
#include <map>

namespace {

const char* kUsage = R"(usage: facetrack COMMAND [ARGS]

commands:
  info                               models, versions, detector in use, stages
  detect IMAGE|DIR|CLIP              faces per image or frame, as JSON lines
  track [CLIP|--camera /dev/videoN]  run the tracker, JSON lines per frame [--overlay out.mp4]
  bench CLIP                         tracker fps and per-stage ms (mean/p50/p99), per-frame plot
  eval-track CLIP...                 tracked share, jitter with/without filter, against dlib
  eval-gaze [--clips CLIP,...]       gaze and blink against teacher labels and synthetic renders
  eval-expressions [CLIP...]         ARKit weights on hand-labelled segments: neutral bias, responses
  calibrate --camera DEV|--input CLIP   measure the user's neutral, ranges and identity into a profile
  send --camera DEV|--input CLIP --protocol vmc,ifacialmocap,openseeface [--to PROTOCOL=HOST:PORT]
                                     stream to avatar apps (VSeeFace, VNyan, Warudo, ...)
  landmarks IMAGE|DIR|CLIP [--box x0,y0,x1,y1]   68 landmarks per face, as JSON lines
  eval-detect DIR                    detector recall and speed on .pts-annotated images
  eval-landmarks DIR                 landmark NME, failure rate, CED plot, against peers

common options:
  --detector auto|yunet|cascade      which face detector (default auto: YuNet if found)
  --yunet PATH                       YuNet 2022mar .onnx (else FACETRACK_YUNET_MODEL, then the usual places)
  --min-score S                      drop detections scoring below S (default 0.5)

'facetrack COMMAND --help' describes one command; docs/cli.md has the details.
)";

}  // namespace

int main(int argc, char** argv) {
    using namespace facetrack::cli;
    const std::map<std::string, std::function<int(const std::vector<std::string>&)>> commands = {
        {"info", runInfo},           {"detect", runDetect},          {"track", runTrack},
        {"landmarks", runLandmarks}, {"eval-detect", runEvalDetect}, {"eval-landmarks", runEvalLandmarks},
        {"bench", runBench},         {"eval-track", runEvalTrack},   {"send", runSend},
        {"calibrate", runCalibrate}, {"eval-gaze", runEvalGaze},     {"eval-expressions", runEvalExpressions}};
    if (argc < 2 || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "help")) {
        std::fputs(kUsage, argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    // Our errors say what went wrong in one line; OpenCV's video backends would add their own
    // warnings and errors before it (GStreamer's for every file it cannot open, the image-sequence
    // backend's for any name without a number).
    cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
    const auto command = commands.find(argv[1]);
    if (command == commands.end()) {
        std::fprintf(stderr, "facetrack: unknown command '%s' (try 'facetrack --help')\n", argv[1]);
        return 2;
    }
    try {
        return command->second(std::vector<std::string>(argv + 2, argv + argc));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "facetrack %s: %s\n", argv[1], e.what());
        return 1;
    }
}
