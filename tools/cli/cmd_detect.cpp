#include "app/media.hpp"
#include "commands.hpp"
#include "json.hpp"

#include "app/image_view.hpp"
#include "facetrack/facetrack.hpp"

#include <iostream>

namespace facetrack::cli {

int runDetect(const std::vector<std::string>& argv) {
    const Args args(argv, kDetectorOptions, {"--help"});
    if (args.has("--help")) {
        std::puts(
            "usage: facetrack detect IMAGE|DIR|CLIP [--detector auto|yunet|cascade] [--yunet PATH] [--min-score S]\n"
            "One JSON line per image or video frame:\n"
            "  {\"image\": PATH, \"frame\": N, \"faces\": [{\"box\": [x0,y0,x1,y1], \"score\": s}]}\n"
            "Boxes are in 0-based pixels of the input.");
        return 0;
    }
    if (args.positional().size() != 1) throw Error("detect needs one IMAGE, DIR or CLIP (see --help)");
    auto detector = createFaceDetector(detectorConfig(args));
    auto reader = MediaReader::open(args.positional()[0]);
    MediaFrame frame;
    while (reader.next(frame)) {
        Json faces = Json::array();
        for (const auto& d : detector->detect(tools::viewOf(frame.bgr))) {
            faces.push_back({{"box", boxJson(d.box)}, {"score", round2(d.score)}});
        }
        std::cout << Json{{"image", frame.source}, {"frame", frame.index}, {"faces", faces}}.dump() << '\n';
    }
    return 0;
}

}  // namespace facetrack::cli
