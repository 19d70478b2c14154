// facetrack calibrate: measure a user's calibration (neutral, ranges, identity)
// from a guided capture on a camera, or from a clip's labelled segments, and
// write it as the profile that track, send and the demo apply.

#include "commands.hpp"

#include "app/image_view.hpp"
#include "common/expression_labels.hpp"
#include "facetrack/facetrack.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>

namespace facetrack::cli {

namespace {

const char* kUsage = R"(usage: facetrack calibrate (--camera /dev/videoN | --input CLIP) [--profile FILE]
                           [--labels CSV | --neutral-at SECONDS] [--seconds S] [tracker options]
Measures the user's calibration and writes it as a profile (default: the user's,
$XDG_CONFIG_HOME/facetrack/profile.json), which track, send and the demo then apply:
  neutral   each shape's mean over the relaxed face
  range     each prompted expression's shapes: the 90th percentile over the prompt becomes the
            value that reads 1, kept when it is at least 0.1 above the neutral
  identity  the face's shape, once estimated (--calibration-frames samples, 5 frames apart)
From a camera: each prompt is printed on stderr for --seconds (default 3; the first second
to get there is not measured). From a clip: its segments in --labels (data/expression_labels.csv's
format, the clip named by its file name; labels that are no prompt are skipped), or
--neutral-at S (the second from S is the neutral; no ranges). Gains and dead zones of an
existing profile at the same path are kept. docs/api.md, "Calibration", has the formula.)";

/// The prompts of each frame of `clip` in `labels` (a frame may be in several segments).
std::multimap<int, std::string> promptsOfClip(const std::string& labelsPath, const std::string& clip) {
    std::multimap<int, std::string> byFrame;
    const std::string name = std::filesystem::path(clip).filename().string();
    for (const auto& seg : tools::readExpressionLabels(labelsPath)) {
        if (seg.clip != name) continue;
        bool isPrompt = false;
        for (const auto& p : calibrationPrompts()) isPrompt = isPrompt || p.name == seg.label;
        if (!isPrompt) continue;
        for (int f = seg.first; f <= seg.last; ++f) byFrame.emplace(f, seg.label);
    }
    if (byFrame.empty()) throw Error(labelsPath + " labels no calibration prompt of '" + name + "'");
    return byFrame;
}

/// The prompt a camera user is holding at `t` seconds since the start, or "" while they get
/// there (the first second of each) and after the last.
std::string cameraPromptAt(double t, double seconds, std::size_t& shown) {
    const auto& prompts = calibrationPrompts();
    const auto index = std::min(static_cast<std::size_t>(t / seconds), prompts.size() - 1);
    if (index >= shown) {
        std::fprintf(stderr, "facetrack calibrate: [%zu/%zu] %s\n", index + 1, prompts.size(), prompts[index].instruction.c_str());
        shown = index + 1;
    }
    return t - static_cast<double>(index) * seconds < 1.0 ? "" : prompts[index].name;
}

void printCalibration(const Calibration& c, const CalibrationCapture& capture) {
    for (const auto& p : calibrationPrompts()) {
        std::printf("%-11s %4d frames", p.name.c_str(), capture.frames(p.name));
        for (const auto& shape : p.shapes) {
            const ShapeCalibration& s = c.shapes[static_cast<std::size_t>(arkitIndex(shape))];
            std::printf("  %s %.2f..%.2f", shape.c_str(), s.neutral, s.full);
        }
        std::printf("\n");
    }
    std::printf("identity    %s\n", c.identity.empty() ? "not estimated (too few well-fitted frames)" : "estimated");
}

}  // namespace

int runCalibrate(const std::vector<std::string>& argv) {
    const Args args(argv, trackingOptions({"--camera", "--input", "--profile", "--labels", "--neutral-at", "--seconds"}),
                    trackingFlags({"--help"}));
    if (args.has("--help")) {
        std::puts(kUsage);
        return 0;
    }
    if (!args.positional().empty()) throw Error("unexpected '" + args.positional()[0] + "' (see --help)");
    if (args.has("--camera") == args.has("--input")) throw Error("give --camera DEVICE or --input CLIP (see --help)");
    if (args.has("--input") && args.has("--labels") == args.has("--neutral-at"))
        throw Error("from a clip, give --labels CSV or --neutral-at SECONDS (see --help)");
    const double neutralAt = args.number("--neutral-at", 0.0);
    if (!(neutralAt >= 0.0 && neutralAt < 1e9)) throw Error("--neutral-at must be seconds, 0 or more");
    const double seconds = args.number("--seconds", 3.0);
    if (!(seconds >= 1.5 && seconds <= 60.0)) throw Error("--seconds must be in [1.5, 60]");
    const std::string profile = args.get("--profile", defaultProfilePath());
    std::error_code ec;
    Calibration base;
    if (std::filesystem::exists(profile, ec)) {
        base = loadCalibration(profile);
        base.identity.clear();  // measured again
    }
    std::multimap<int, std::string> labelled;
    if (args.has("--labels")) labelled = promptsOfClip(args.get("--labels"), args.get("--input"));

    Tracker tracker(tools::trackingModels(args), trackerConfig(args));  // no calibration: the weights as estimated
    MediaReader reader = args.has("--camera") ? MediaReader::openCamera({args.get("--camera")}) : MediaReader::open(args.get("--input"));
    std::fprintf(stderr, "facetrack calibrate: %s\n", reader.describe().c_str());
    CalibrationCapture capture(base);
    MediaFrame frame;
    FrameResult result;
    std::size_t shown = 0;
    double start = -1.0;
    for (int f = 0; reader.next(frame); ++f) {
        tracker.process(tools::viewOf(frame.bgr), frame.time_s, result);
        if (start < 0.0) start = frame.time_s;
        std::vector<std::string> prompts;
        if (reader.isCamera()) {
            const double t = frame.time_s - start;
            if (t >= seconds * static_cast<double>(calibrationPrompts().size())) break;
            const std::string p = cameraPromptAt(t, seconds, shown);
            if (!p.empty()) prompts.push_back(p);
        } else if (args.has("--labels")) {
            for (auto [it, end] = labelled.equal_range(f); it != end; ++it) prompts.push_back(it->second);
        } else if (frame.time_s >= neutralAt && frame.time_s < neutralAt + 1.0) {
            prompts.push_back("neutral");
        }
        if (result.faces.empty() || !result.faces[0].expression) continue;
        for (const auto& p : prompts) capture.add(p, *result.faces[0].expression);
    }
    Calibration calibration = capture.result();
    calibration.identity = tracker.calibration().identity;
    saveCalibration(calibration, profile);
    printCalibration(calibration, capture);
    std::fprintf(stderr, "facetrack calibrate: wrote %s\n", profile.c_str());
    return 0;
}

}  // namespace facetrack::cli
