// train_facemark: trains OpenCV's FacemarkLBF, with OpenCV's default
// parameters, on facetrack's 300-W training split, as the peer that
// `facetrack eval-landmarks --facemark` compares against. Faces are found with
// the same YuNet detector facetrack uses.
//
//   train_facemark [--data ../shared/data/faces300w] [--out facemark_lbf.yaml]

#include "app/args.hpp"
#include "app/tool_main.hpp"
#include "common/faces300w.hpp"
#include "core/environment.hpp"
#include "core/image.hpp"
#include "core/pts.hpp"
#include "facetrack/detector.hpp"
#include "facetrack/version.hpp"

#include <opencv2/face.hpp>
#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <cstdio>

namespace facetrack::tools {
namespace {

/// FacemarkLBF's face detector hook: YuNet boxes as cv::Rects.
bool yunetFaces(cv::InputArray image, cv::OutputArray faces, void* detector) {
    std::vector<cv::Rect> rects;
    for (const auto& d : static_cast<FaceDetector*>(detector)->detect(core::viewOf(image.getMat()))) {
        rects.emplace_back(cv::Point(cvRound(d.box.x0), cvRound(d.box.y0)), cv::Point(cvRound(d.box.x1), cvRound(d.box.y1)));
    }
    cv::Mat(rects).copyTo(faces);
    return true;
}

int run(int argc, char** argv) {
    const Args args(std::vector<std::string>(argv + 1, argv + argc), {"--data", "--out"}, {"--help"});
    if (args.has("--help")) {
        std::puts("usage: train_facemark [--data ../shared/data/faces300w] [--out facemark_lbf.yaml]");
        return 0;
    }
    setLogHandler({});
    const std::string data = faces300wRoot(args.get("--data"));
    const std::string out = args.get("--out", "facemark_lbf.yaml");

    DetectorConfig config;
    config.kind = DetectorKind::YuNet;
    auto detector = createFaceDetector(config);
    cv::face::FacemarkLBF::Params params;  // OpenCV's defaults
    params.model_filename = out;
    params.verbose = true;
    auto facemark = cv::face::FacemarkLBF::create(params);
    facemark->setFaceDetector(yunetFaces, detector.get());

    const auto train = list300W(data, Split::Train);
    for (const auto& face : train) {
        const cv::Mat image = cv::imread(face.image, cv::IMREAD_COLOR);
        if (image.empty()) throw Error("cannot read '" + face.image + "'");
        const core::Shape2 pts = core::readPts(face.pts);
        std::vector<cv::Point2f> points;
        for (int i = 0; i < pts.cols(); ++i) points.emplace_back(pts(0, i), pts(1, i));
        facemark->addTrainingSample(image, points);
    }
    std::printf("training FacemarkLBF on %zu faces (validation and test held out)\n", train.size());
    const auto start = std::chrono::steady_clock::now();
    facemark->training();
    std::printf("wrote %s in %.0f s\n", out.c_str(), std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    return 0;
}

}  // namespace
}  // namespace facetrack::tools

int main(int argc, char** argv) { return facetrack::tools::runTool("train_facemark", facetrack::tools::run, argc, argv); }
