#include "commands.hpp"
#include "json.hpp"
#include "app/media.hpp"

#include "app/image_view.hpp"
#include "facetrack/facetrack.hpp"
#include "landmarks/lbf.hpp"

#include <opencv2/imgproc.hpp>

#include <iostream>
#include <sstream>

namespace facetrack::cli {

namespace {

const char* kUsage = R"(usage: facetrack landmarks IMAGE|DIR|CLIP [--box x0,y0,x1,y1] [--model FILE]
                           [--detector auto|yunet|cascade] [--yunet PATH] [--min-score S]
68 landmarks (iBUG order, 0-based pixels) for each face, one JSON line per image or frame:
  {"image": PATH, "frame": N, "faces": [{"box": [x0,y0,x1,y1], "score": s, "landmarks": [[x,y], ...]}]}
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
    valued.insert({"--box", "--model"});
    const Args args(argv, valued, {"--help"});
    if (args.has("--help")) {
        std::puts(kUsage);
        return 0;
    }
    if (args.positional().size() != 1) throw Error("landmarks needs one IMAGE, DIR or CLIP (see --help)");
    const std::optional<Box> givenBox = args.has("--box") ? std::optional(parseBox(args.get("--box"))) : std::nullopt;
    auto reader = MediaReader::open(args.positional()[0]);
    const auto model = args.has("--model") ? LandmarkModel::load(args.get("--model")) : LandmarkModel::loadDefault();
    std::unique_ptr<FaceDetector> detector;
    if (!givenBox) detector = createFaceDetector(detectorConfig(args));
    const std::string prior = detector ? detector->kind() : "yunet";

    MediaFrame frame;
    cv::Mat gray;
    while (reader.next(frame)) {
        cv::cvtColor(frame.bgr, gray, cv::COLOR_BGR2GRAY);
        std::vector<Detection> faces;
        if (givenBox) faces.push_back({*givenBox, 0.f});
        else faces = detector->detect(tools::viewOf(frame.bgr));
        Json list = Json::array();
        for (const auto& face : faces) {
            const auto shape = landmarks::alignLandmarks(model->data(), gray,
                                                         landmarks::shapeFromBox(model->data(), face.box, prior));
            list.push_back({{"box", boxJson(face.box)},
                            {"score", givenBox ? Json(nullptr) : Json(round2(face.score))},
                            {"landmarks", landmarksJson(landmarks::toLandmarks68(shape))}});
        }
        std::cout << Json{{"image", frame.source}, {"frame", frame.index}, {"faces", list}}.dump() << '\n';
    }
    return 0;
}

}  // namespace facetrack::cli
