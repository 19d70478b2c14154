#include "app/media.hpp"
#include "commands.hpp"
#include "common/faces300w.hpp"

#include "app/image_view.hpp"
#include "core/pts.hpp"
#include "facetrack/facetrack.hpp"

#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

namespace fs = std::filesystem;

namespace facetrack::cli {

namespace {

const char* kUsage = R"(usage: facetrack eval-detect DIR [--detector auto|yunet|cascade] [--yunet PATH] [--min-score S]
Runs the detector on every image below DIR that has a .pts file beside it.
A face counts as found when a detection's box contains the landmarks' centroid
and its size, sqrt(w*h), is 0.5-2x that of the landmarks' bounding box.
Prints recall and mean milliseconds per image, per subfolder and overall.)";

struct Tally {
    int images = 0;
    int found = 0;
    int detections = 0;
    double ms = 0.0;
};

void print(const std::string& name, const Tally& t) {
    std::printf("%-22s %6d %8.1f%% %10.2f %8.2f\n", name.c_str(), t.images, 100.0 * t.found / std::max(1, t.images),
                t.ms / std::max(1, t.images), double(t.detections) / std::max(1, t.images));
}

}  // namespace

int runEvalDetect(const std::vector<std::string>& argv) {
    const Args args(argv, kDetectorOptions, {"--help"});
    if (args.has("--help")) {
        std::puts(kUsage);
        return 0;
    }
    if (args.positional().size() != 1) throw Error("eval-detect needs one DIR (see --help)");
    const std::string dir = args.positional()[0];
    auto detector = createFaceDetector(detectorConfig(args));
    if (!fs::is_directory(dir)) throw Error("not a folder: '" + dir + "'");

    std::map<std::string, Tally> subsets;
    Tally all;
    for (const auto& image : listImages(dir)) {
        const std::string pts = fs::path(image).replace_extension(".pts").string();
        if (!fs::exists(pts)) continue;
        const cv::Mat bgr = cv::imread(image, cv::IMREAD_COLOR);
        if (bgr.empty()) throw Error("cannot read image '" + image + "'");
        const auto points = core::readPts(pts);

        const auto start = std::chrono::steady_clock::now();
        const auto detections = detector->detect(tools::viewOf(bgr));
        const std::chrono::duration<double, std::milli> elapsed = std::chrono::steady_clock::now() - start;

        bool found = false;
        for (const auto& d : detections) found = found || tools::boxMatchesFace(d.box, points);
        const std::string subset = fs::relative(fs::path(image).parent_path(), dir).string();
        for (Tally* t : {&subsets[subset], &all}) {
            t->images += 1;
            t->found += found ? 1 : 0;
            t->detections += static_cast<int>(detections.size());
            t->ms += elapsed.count();
        }
    }
    if (all.images == 0) throw Error("no images with .pts files below '" + dir + "'");
    std::printf("detector: %s (%s)\n", detector->kind().c_str(), detector->modelPath().c_str());
    std::printf("%-22s %6s %9s %10s %8s\n", "subset", "images", "recall", "ms/image", "boxes");
    for (const auto& [name, tally] : subsets) print(name, tally);
    print("all", all);
    return 0;
}

}  // namespace facetrack::cli
