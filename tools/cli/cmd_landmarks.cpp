#include "app/media.hpp"
#include "commands.hpp"
#include "json.hpp"

#include "app/image_view.hpp"
#include "facetrack/facetrack.hpp"
#include "still_landmarks.hpp"

#include <opencv2/imgproc.hpp>

#include <iostream>
#include <sstream>

namespace facetrack::cli {

namespace {

const char* kUsage = R"(usage: facetrack landmarks IMAGE|DIR|CLIP [--box x0,y0,x1,y1] [--model FILE]
                           [--refiner FILE|none] [--cascade FILE|none] [--lbf-only]
                           [--detector auto|yunet|cascade] [--yunet PATH] [--min-score S]
68 landmarks (iBUG order, 0-based pixels) for each face, one JSON line per image or frame:
  {"image": PATH, "frame": N, "method": M, "faces": [{"box": [x0,y0,x1,y1], "score": s, "landmarks": [[x,y], ...]}]}
Each image or frame on its own. The landmarks are the tracker's: LBF, the CNN landmark refiner
(--refiner, default: the shipped landmark_refiner.ftm), the fit and a CNN file's landmark net
(--cascade; the shipped cnn_cascade.ftm has none), or LBF's alone with --lbf-only or without such
nets, and for a face whose fit does not hold; "method" says which.
--box skips detection and starts from that box (drawn like YuNet's; score is null).
--model defaults to landmarks_lbf.ftm in the model directory.)";

Box parseBox(const std::string& text) {
    std::stringstream in(text);
    std::vector<float> v;
    for (std::string part; std::getline(in, part, ',');) {
        try {
            std::size_t used = 0;
            v.push_back(std::stof(part, &used));
            if (used != part.size()) v.clear();
        } catch (const std::exception&) {
            v.clear();
            break;
        }
    }
    if (v.size() != 4 || !(v[2] > v[0]) || !(v[3] > v[1])) {
        throw Error("--box expects x0,y0,x1,y1 with x1 > x0 and y1 > y0, got '" + text + "'");
    }
    return {v[0], v[1], v[2], v[3]};
}

}  // namespace

int runLandmarks(const std::vector<std::string>& argv) {
    auto valued = kDetectorOptions;
    valued.insert({"--box", "--model", "--refiner", "--cascade"});
    const Args args(argv, valued, {"--help", "--lbf-only"});
    if (args.has("--help")) {
        std::puts(kUsage);
        return 0;
    }
    if (args.positional().size() != 1) throw Error("landmarks needs one IMAGE, DIR or CLIP (see --help)");
    const std::optional<Box> givenBox = args.has("--box") ? std::optional(parseBox(args.get("--box"))) : std::nullopt;
    const auto model = args.has("--model") ? LandmarkModel::load(args.get("--model")) : LandmarkModel::loadDefault();
    std::unique_ptr<FaceDetector> detector;
    if (!givenBox) detector = createFaceDetector(detectorConfig(args));
    StillLandmarks still(model, args.get("--refiner", ""), args.get("--cascade", ""), args.has("--lbf-only"),
                         detector ? detector->kind() : "yunet");
    auto reader = MediaReader::open(args.positional()[0]);

    MediaFrame frame;
    cv::Mat gray;
    while (reader.next(frame)) {
        cv::cvtColor(frame.bgr, gray, cv::COLOR_BGR2GRAY);
        std::vector<Detection> faces;
        if (givenBox) faces.push_back({*givenBox, 0.f});
        else faces = detector->detect(tools::viewOf(frame.bgr));
        Json list = Json::array();
        bool anyDropped = false;
        for (const auto& face : faces) {
            bool dropped = false;
            const Landmarks68 points = still.of(frame.bgr, gray, face.box, &dropped);
            anyDropped |= dropped;
            list.push_back({{"box", boxJson(face.box)},
                            {"score", givenBox ? Json(nullptr) : Json(round2(face.score))},
                            {"landmarks", landmarksJson(points)}});
        }
        const std::string method = anyDropped ? still.method() + " (LBF where the fit did not hold)" : still.method();
        std::cout << Json{{"image", frame.source}, {"frame", frame.index}, {"method", method}, {"faces", list}}.dump() << '\n';
    }
    return 0;
}

}  // namespace facetrack::cli
