#include "ced_plot.hpp"
#include "commands.hpp"
#include "common/faces300w.hpp"
#include "json.hpp"
#include "model/internals.hpp"
#include "stats.hpp"
#include "still_landmarks.hpp"

#include "app/image_view.hpp"
#include "core/pts.hpp"
#include "data/dense/label_table.hpp"
#include "facetrack/facetrack.hpp"
#include "landmarks/lbf.hpp"

#include <dlib/image_processing.h>
#include <dlib/opencv.h>
#include <opencv2/face.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <numeric>
#include <optional>

namespace fs = std::filesystem;

namespace facetrack::cli {

namespace {

const char* kUsage = R"(usage: facetrack eval-landmarks DIR [--split train|validation|test] [--model FILE]
                                [--refiner FILE|none] [--cascade FILE|none] [--lbf-only] [--facemark FILE] [--dlib FILE|none]
                                [--plot ced.png] [--max-error 0.08] [--landmark-starts N]
                                [--tracked-frames N] [--points-out FILE.csv] [--sequences] [--poses FILE]
Fits 68 landmarks on every face below DIR that has a .pts file, starting from its
YuNet box, and compares them with the annotation. With --split, DIR is the 300-W
root (../shared/data/faces300w) and only that split is read (docs/landmarks.md).
Methods, side by side with the same boxes:
  facetrack LBF + refiner  what the tracker reports: LBF, the CNN landmark refiner (--refiner,
                           default: the shipped landmark_refiner.ftm), the fit, and a CNN file's
                           landmark net (--cascade; the shipped cnn_cascade.ftm has none);
                           --lbf-only leaves them out; a face whose fit does not hold keeps
                           LBF's landmarks ("dropped")
  facetrack LBF, N starts  --model (default: the shipped landmarks_lbf.ftm) from --landmark-starts N
                           starts, averaged (default 3, the tracker's), and from one start
  facetrack tracked        --tracked-frames N: the tracker (LBF + fit, no CNN, no filter) given the
                           box on the first of N copies of the image, the landmarks of the last:
                           tracking mode, where each frame's LBF starts from the previous fit
  OpenCV FacemarkLBF       --facemark FILE, a model trained by tools' train_facemark
  dlib shape_predictor     --dlib FILE (default /usr/share/dlib/shape_predictor_68_face_landmarks.dat)
Prints per method: faces, mean and median NME (300-W: mean point error over the
outer-eye-corner distance), failure rate (NME > max error), AUC of the CED up to
the max error, and ms per face, then the mean NME of each face region (jaw, brows,
nose, eyes, mouth). --plot writes the CED curves as a PNG; --points-out writes every
face's points, one CSV row per face and method (image, method, x0, y0, ..., x67, y67;
the annotation's rows have method "annotation").
When DIR holds a poses.csv (image path below DIR, yaw_deg), as the large-pose sets of
build/tools/make_profiled_faces do, also the mean NME over sqrt(w h) of the annotation's
box by 15-degree bin of |yaw| (the large-pose figure of docs/landmarks.md).
--poses FILE takes each image's yaw from FILE instead: a poses.csv, or a table of label_dense
(its key is the path below DIR). So `eval-landmarks ../shared/data/faces300w --split test --poses build/dense_labels/faces300w.csv`
bins the photographed faces by the dense teacher labels' yaw (a teacher's estimate, not ground truth);
faces the file has no yaw for are left out of the bins and counted.
--sequences: each folder's images, in name order, are also a clip at 30 fps (as
make_profiled_faces --turn-clips writes head turns): the tracker, as a video application
runs it (its own detector until it finds the face, then tracking mode; no filter), follows
the face through it. Adds, over every frame (with poses.csv, by |yaw| bin): the share of
frames where it follows no face, the box NME where it does, and with poses.csv the error of the
head's yaw once each clip's constant difference to poses.csv (another convention) is removed, and
how far the head's yaw turns per degree of poses.csv's within each clip (1: as far).)";

using core::Shape2;

constexpr std::size_t kYawBins = 6;  // |yaw| 0-15, ..., 75-90 deg

/// A poses file as {image path below DIR: yaw in degrees}: a poses.csv (image,yaw_deg), or a label_dense
/// table (key, split, ..., yaw_deg, ...). Empty when `required` is false and there is no file.
std::map<std::string, double> readPoses(const std::string& path, bool required) {
    std::map<std::string, double> yaw;
    std::ifstream in(path);
    if (!in) {
        if (required) throw Error("cannot read poses '" + path + "'");
        return yaw;
    }
    std::string line;
    std::getline(in, line);
    if (line.rfind("key,split,", 0) == 0) {
        const dense::LabelTable table = dense::readLabelTable(path);
        const int degrees = table.column("yaw_deg");
        if (degrees < 0) throw Error("'" + path + "': the labels have no yaw_deg column");
        for (const auto& row : table.rows) yaw[row.key] = row.values[static_cast<std::size_t>(degrees)];
        return yaw;
    }
    if (line != "image,yaw_deg") throw Error("'" + path + "': expected the header image,yaw_deg (or a label_dense table)");
    while (std::getline(in, line)) {
        const auto comma = line.rfind(',');
        char* end = nullptr;
        const double deg = comma == std::string::npos ? 0.0 : std::strtod(line.c_str() + comma + 1, &end);
        if (comma == std::string::npos || end == line.c_str() + comma + 1 || !std::isfinite(deg)) {
            throw Error("'" + path + "': malformed line '" + line + "'");
        }
        yaw[line.substr(0, comma)] = deg;
    }
    return yaw;
}

/// One landmark method under evaluation.
struct Method {
    std::string name;
    std::function<Shape2(const cv::Mat& bgr, const cv::Mat& gray, const Box& box)> fit;
    std::vector<double> nmes{};
    std::array<std::vector<double>, kYawBins> box_nmes_by_yaw{};    ///< with poses.csv: per |yaw| bin, NME over sqrt(box)
    std::array<double, std::size(core::kRegions68)> region_sums{};  ///< per region, the sum over faces of its mean point error
    double ms = 0.0;

    Method(std::string n, std::function<Shape2(const cv::Mat&, const cv::Mat&, const Box&)> f) : name(std::move(n)), fit(std::move(f)) {}
};

Method ourLbf(std::shared_ptr<const LandmarkModel> model, int starts) {
    return {"facetrack LBF, " + std::to_string(starts) + (starts == 1 ? " start" : " starts"),
            [model, starts](const cv::Mat&, const cv::Mat& gray, const Box& box) {
                return Shape2(landmarks::alignFromStarts(model::dataOf(*model), gray,
                                                         landmarks::shapeFromBox(model::dataOf(*model), box, "yunet"), starts));
            }};
}

/// The tracker in tracking mode on a still face: the box starts it, then `frames` - 1 more copies
/// of the image are tracked. A face it drops keeps the first copy's LBF landmarks, counted in `dropped`.
Method trackedStill(std::shared_ptr<const LandmarkModel> model, int starts, int frames, int& dropped) {
    TrackerConfig config;
    config.filter.enabled = false;
    config.max_faces = 1;
    config.landmark_starts = starts;
    auto tracker = std::make_shared<Tracker>(Models{FaceModel::loadDefault(), model, nullptr, nullptr, nullptr}, config);
    auto result = std::make_shared<FrameResult>();
    return {"facetrack tracked, frame " + std::to_string(frames),
            [model, starts, frames, tracker, result, &dropped](const cv::Mat& bgr, const cv::Mat& gray, const Box& box) {
                tracker->reset();
                for (int f = 0; f < frames; ++f) {
                    const double t = f / 30.0;
                    if (f == 0) tracker->process(tools::viewOf(bgr), t, {box}, *result);
                    else tracker->process(tools::viewOf(bgr), t, {}, *result);
                    if (result->faces.empty() || !result->faces[0].landmarks) {
                        ++dropped;
                        return Shape2(landmarks::alignFromStarts(model::dataOf(*model), gray,
                                                                 landmarks::shapeFromBox(model::dataOf(*model), box, "yunet"), starts));
                    }
                }
                return Shape2(core::fromLandmarks68(*result->faces[0].landmarks));
            }};
}

Method facemarkLbf(const std::string& path) {
    if (!fs::exists(path)) throw Error("FacemarkLBF model '" + path + "' does not exist");
    cv::face::FacemarkLBF::Params params;
    params.verbose = false;
    cv::Ptr<cv::face::FacemarkLBF> facemark = cv::face::FacemarkLBF::create(params);
    facemark->loadModel(path);
    return {"OpenCV FacemarkLBF", [facemark](const cv::Mat& bgr, const cv::Mat&, const Box& box) {
                std::vector<cv::Rect> faces = {
                    cv::Rect(cv::Point(cvRound(box.x0), cvRound(box.y0)), cv::Point(cvRound(box.x1), cvRound(box.y1)))};
                std::vector<std::vector<cv::Point2f>> points;
                if (!facemark->fit(bgr, faces, points) || points.empty() || points[0].size() != 68) {
                    throw Error("FacemarkLBF failed to fit a face");
                }
                Shape2 s(2, 68);
                for (int i = 0; i < 68; ++i) s.col(i) = Eigen::Vector2f(points[0][i].x, points[0][i].y);
                return s;
            }};
}

Method dlibShapePredictor(const std::string& path, bool seenInTraining) {
    auto predictor = std::make_shared<dlib::shape_predictor>();
    try {
        dlib::deserialize(path) >> *predictor;
    } catch (const std::exception& e) {
        throw Error("cannot load dlib model '" + path + "': " + e.what());
    }
    return {std::string("dlib shape_predictor") + (seenInTraining ? " (seen in training)" : ""),
            [predictor](const cv::Mat&, const cv::Mat& gray, const Box& box) {
                const dlib::cv_image<unsigned char> image(gray);
                const dlib::full_object_detection d = (*predictor)(
                    image, dlib::rectangle(std::lround(box.x0), std::lround(box.y0), std::lround(box.x1), std::lround(box.y1)));
                Shape2 s(2, 68);
                for (int i = 0; i < 68; ++i) s.col(i) = Eigen::Vector2f(d.part(i).x(), d.part(i).y());
                return s;
            }};
}

/// --sequences: the tracker following each clip's face, per |yaw| bin (all frames in bin 0 without poses.csv).
struct FollowedFrames {
    std::array<int, kYawBins> frames{}, without_face{};
    std::array<std::vector<double>, kYawBins> box_nmes{};
    double ms = 0.0;
    /// With poses.csv: the head's yaw error, |yaw - label - m| with m the clip's median of
    /// yaw - label (the two conventions' constant difference, one per clip: offsets).
    std::array<std::vector<double>, kYawBins> yaw_errors{};
    std::vector<double> offsets;
    /// Every frame's label and yaw less their clip's means: the slope of the line through them is
    /// how far the tracker's yaw turns per degree the clip's poses turn (1: as far).
    std::vector<double> turn_label, turn_yaw;
    struct Frame {
        double yaw, label;
        std::size_t bin;
    };
    std::vector<Frame> clip;  ///< the current clip's frames with a pose

    void endClip() {
        if (clip.empty()) return;
        std::vector<double> d;
        for (const auto& f : clip) d.push_back(f.yaw - f.label);
        std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
        const double offset = d[d.size() / 2];
        offsets.push_back(offset);
        for (const auto& f : clip) yaw_errors[f.bin].push_back(std::abs(f.yaw - f.label - offset));
        double yawMean = 0.0, labelMean = 0.0;
        for (const auto& f : clip) yawMean += f.yaw, labelMean += f.label;
        yawMean /= static_cast<double>(clip.size());
        labelMean /= static_cast<double>(clip.size());
        for (const auto& f : clip) turn_label.push_back(f.label - labelMean), turn_yaw.push_back(f.yaw - yawMean);
        clip.clear();
    }
};

/// "  x.xx% (   n)" per bin, "-" where a bin is empty; `percent` scales by 100.
void printBins(const char* label, const std::array<std::vector<double>, kYawBins>& bins, bool percent) {
    std::printf("%-40s", label);
    for (const auto& bin : bins) {
        if (bin.empty()) {
            std::printf("  %-14s", "-");
            continue;
        }
        const double mean = std::accumulate(bin.begin(), bin.end(), 0.0) / static_cast<double>(bin.size());
        if (percent) std::printf("  %6.2f%% (%4zu)", 100.0 * mean, bin.size());
        else std::printf("  %5.2f deg (%4zu)", mean, bin.size());
    }
    std::putchar('\n');
}

void writePointsRow(std::ofstream& out, const std::string& image, const std::string& method, const Shape2& points) {
    out << '"' << image << "\",\"" << method << '"';  // quoted: method names have commas
    for (int i = 0; i < points.cols(); ++i) out << ',' << points(0, i) << ',' << points(1, i);
    out << '\n';
}

}  // namespace

int runEvalLandmarks(const std::vector<std::string>& argv) {
    const Args args(argv,
                    {"--split", "--model", "--refiner", "--cascade", "--facemark", "--dlib", "--plot", "--max-error", "--yunet",
                     "--landmark-starts", "--tracked-frames", "--points-out", "--poses"},
                    {"--help", "--lbf-only", "--sequences"});
    if (args.has("--help")) {
        std::puts(kUsage);
        return 0;
    }
    if (args.positional().size() != 1) throw Error("eval-landmarks needs one DIR (see --help)");
    const std::string dir = args.positional()[0];
    const double maxError = args.number("--max-error", 0.08);
    if (!(maxError > 0.0 && maxError <= 1.0)) throw Error("--max-error must be in (0, 1]");
    if (args.has("--split")) tools::parseSplit(args.get("--split"));  // checked before anything opens
    const std::string posesPath = args.get("--poses", dir + "/poses.csv");
    std::map<std::string, double> poses = args.has("--poses") ? readPoses(posesPath, true) : std::map<std::string, double>();

    std::vector<Method> methods;
    const auto lbf = args.has("--model") ? LandmarkModel::load(args.get("--model")) : LandmarkModel::loadDefault();
    const int starts = args.integer("--landmark-starts", TrackerConfig{}.landmark_starts);
    landmarks::checkStartCount(starts, "--landmark-starts");
    auto pipeline = std::make_shared<StillLandmarks>(lbf, args.get("--refiner", ""), args.get("--cascade", ""), args.has("--lbf-only"),
                                                     "yunet", starts);
    int dropped = 0;
    if (pipeline->usesPipeline()) {
        methods.emplace_back(pipeline->method(), [pipeline, &dropped](const cv::Mat& bgr, const cv::Mat& gray, const Box& box) {
            bool lost = false;
            const Landmarks68 points = pipeline->of(bgr, gray, box, &lost);
            dropped += lost;
            return Shape2(core::fromLandmarks68(points));
        });
    }
    methods.push_back(ourLbf(lbf, starts));
    int trackedDropped = 0;
    const int trackedFrames = args.integer("--tracked-frames", 0);
    if (trackedFrames < 0 || trackedFrames > 1000) throw Error("--tracked-frames must be in 0..1000");
    if (trackedFrames > 0) methods.push_back(trackedStill(lbf, starts, trackedFrames, trackedDropped));
    if (starts != 1) methods.push_back(ourLbf(lbf, 1));
    if (args.has("--facemark")) methods.push_back(facemarkLbf(args.get("--facemark")));
    const std::string dlibPath = args.get("--dlib", "/usr/share/dlib/shape_predictor_68_face_landmarks.dat");
    if (args.has("--dlib") && dlibPath != "none" && !fs::exists(dlibPath))
        throw Error("no dlib model '" + dlibPath + "' (--dlib none skips dlib)");
    if (dlibPath != "none" && fs::exists(dlibPath)) {
        // dlib's model was trained on the 300-W training images; only the common test set is new to it.
        const bool seen = !args.has("--split") || args.get("--split") != "test";
        methods.push_back(dlibShapePredictor(dlibPath, seen));
    }

    DetectorConfig config;
    config.kind = DetectorKind::YuNet;
    config.yunet_model = args.get("--yunet");
    auto detector = createFaceDetector(config);
    const auto faces = args.has("--split") ? tools::list300W(dir, tools::parseSplit(args.get("--split"))) : tools::listAnnotated(dir);
    if (!args.has("--poses") && !args.has("--split")) poses = readPoses(posesPath, false);

    std::ofstream pointsOut;
    if (args.has("--points-out")) {
        pointsOut.open(args.get("--points-out"));
        if (!pointsOut) throw Error("cannot write '" + args.get("--points-out") + "'");
        pointsOut << "image,method";
        for (int i = 0; i < 68; ++i) pointsOut << ",x" << i << ",y" << i;
        pointsOut << '\n';
        pointsOut.precision(7);
    }

    const bool sequences = args.has("--sequences");
    FollowedFrames followed;
    std::array<int, kYawBins> missedByYaw{};
    int withoutYaw = 0;  // --poses: faces the file has no yaw for
    int missed = 0;
    cv::Mat gray;
    for (std::size_t k = 0; k < faces.size(); ++k) {
        const cv::Mat bgr = cv::imread(faces[k].image, cv::IMREAD_COLOR);
        if (bgr.empty()) throw Error("cannot read image '" + faces[k].image + "'");
        const Shape2 truth = core::readPts(faces[k].pts);
        if (truth.cols() != 68) throw Error("'" + faces[k].pts + "' does not have 68 points");
        std::optional<double> yaw;
        std::optional<std::size_t> yawBin;
        if (!poses.empty()) {
            const auto pose = poses.find(fs::relative(faces[k].image, dir).string());
            // A set's own poses.csv names every image; a teacher's table may lack a face it did not label.
            if (pose == poses.end() && !args.has("--poses")) throw Error("'" + faces[k].image + "' is not in " + posesPath);
            if (pose != poses.end()) {
                yaw = pose->second;
                yawBin = std::min(kYawBins - 1, static_cast<std::size_t>(std::abs(*yaw) / 15.0));
            } else {
                ++withoutYaw;
            }
        }
        if (sequences) {  // every frame, with or without a YuNet box: the tracker does not need one
            const bool newClip = k == 0 || faces[k].subset != faces[k - 1].subset;
            if (newClip) followed.endClip();
            const auto start = std::chrono::steady_clock::now();
            const FaceResult* face = pipeline->followed(bgr, newClip);
            followed.ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
            const std::size_t bin = yawBin.value_or(0);
            ++followed.frames[bin];
            if (face) followed.box_nmes[bin].push_back(core::nmeBox(Shape2(core::fromLandmarks68(*face->landmarks)), truth));
            else ++followed.without_face[bin];
            if (face && face->pose && yaw) followed.clip.push_back({face->pose->euler_deg.y, *yaw, bin});
        }
        const auto box = tools::matchingBox(detector->detect(tools::viewOf(bgr)), truth);
        if (!box) {
            ++missed;
            if (yawBin) ++missedByYaw[*yawBin];
            continue;
        }
        cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
        if (pointsOut.is_open()) writePointsRow(pointsOut, faces[k].image, "annotation", truth);
        for (auto& m : methods) {
            const auto start = std::chrono::steady_clock::now();
            const Shape2 fitted = m.fit(bgr, gray, *box);
            m.ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
            const Eigen::VectorXf errors = core::pointErrors68(fitted, truth);
            m.nmes.push_back(errors.mean());
            if (yawBin) m.box_nmes_by_yaw[*yawBin].push_back(core::nmeBox(fitted, truth));
            for (std::size_t r = 0; r < m.region_sums.size(); ++r) {
                const auto& region = core::kRegions68[r];
                m.region_sums[r] += errors.segment(region.first, region.end - region.first).mean();
            }
            if (pointsOut.is_open()) writePointsRow(pointsOut, faces[k].image, m.name, fitted);
        }
        if ((k + 1) % 50 == 0 || k + 1 == faces.size()) {
            std::fprintf(stderr, "\r%zu/%zu faces", k + 1, faces.size());
        }
    }
    std::fputc('\n', stderr);
    followed.endClip();

    std::printf("%zu faces, %d without a YuNet box (left out)\n", faces.size(), missed);
    if (pipeline->usesPipeline())
        std::printf("%s: %d faces dropped by the fit (LBF's landmarks kept)\n", pipeline->method().c_str(), dropped);
    if (trackedFrames > 0) std::printf("facetrack tracked: %d faces dropped by the tracker (LBF's landmarks kept)\n", trackedDropped);
    std::printf("%-40s %6s %9s %9s %10s %9s %9s\n", "method", "faces", "mean NME", "median", "fail@8%", "AUC@8%", "ms/face");
    std::vector<CedCurve> curves;
    for (const auto& m : methods) {
        const ErrorSummary s = summarize(m.nmes, maxError);
        std::printf("%-40s %6zu %8.2f%% %8.2f%% %9.2f%% %9.4f %9.3f\n", m.name.c_str(), m.nmes.size(), 100 * s.mean, 100 * s.median,
                    100 * s.failure_rate, s.auc, m.ms / std::max<std::size_t>(1, m.nmes.size()));
        char label[160];
        std::snprintf(label, sizeof label, "%s: mean %.2f%%, AUC %.3f", m.name.c_str(), 100 * s.mean, s.auc);
        curves.push_back({label, m.nmes});
    }
    std::printf("\nmean NME by region\n%-40s", "method");
    for (const auto& region : core::kRegions68) std::printf(" %8s", region.name);
    for (const auto& m : methods) {
        std::printf("\n%-40s", m.name.c_str());
        for (double sum : m.region_sums) std::printf(" %7.2f%%", 100 * sum / std::max<std::size_t>(1, m.nmes.size()));
    }
    std::putchar('\n');
    if (!poses.empty()) {
        std::printf("\nmean NME over sqrt(w h) of the annotation's box, by |yaw| (faces)\n%-40s", "method");
        for (std::size_t b = 0; b < kYawBins; ++b) std::printf("  %2zu-%2zu deg     ", 15 * b, 15 * b + 15);
        std::putchar('\n');
        for (const auto& m : methods) printBins(m.name.c_str(), m.box_nmes_by_yaw, true);
        std::printf("%-40s", "frames without a YuNet box (left out)");
        for (int n : missedByYaw) std::printf("  %-14d", n);
        std::putchar('\n');
        if (withoutYaw > 0) std::printf("(%d faces without a yaw in %s: left out of the bins)\n", withoutYaw, posesPath.c_str());
    }
    if (sequences) {
        const int frames = std::accumulate(followed.frames.begin(), followed.frames.end(), 0);
        const int without = std::accumulate(followed.without_face.begin(), followed.without_face.end(), 0);
        std::vector<double> all;
        for (const auto& bin : followed.box_nmes) all.insert(all.end(), bin.begin(), bin.end());
        std::printf(
            "\n%s followed through each folder's frames (--sequences): %d frames, %.2f ms a frame, no face on %d (%.1f %%),"
            " box NME %.2f %% where it follows one\n",
            pipeline->method().c_str(), frames, followed.ms / std::max(1, frames), without, 100.0 * without / std::max(1, frames),
            all.empty() ? 0.0 : 100.0 * std::accumulate(all.begin(), all.end(), 0.0) / static_cast<double>(all.size()));
        if (!poses.empty()) {
            printBins("by |yaw|: box NME (frames followed)", followed.box_nmes, true);
            std::printf("%-40s", "by |yaw|: frames without a face");
            for (std::size_t b = 0; b < kYawBins; ++b)
                std::printf("  %-14s", (std::to_string(followed.without_face[b]) + " of " + std::to_string(followed.frames[b])).c_str());
            std::putchar('\n');
            printBins("by |yaw|: head yaw error, offset removed", followed.yaw_errors, false);
            std::vector<double> offsets = followed.offsets;
            std::sort(offsets.begin(), offsets.end());
            if (!offsets.empty()) {
                std::printf(
                    "(the yaw error: |yaw - poses.csv's yaw - each clip's median difference|; the median differences of the %zu clips"
                    " lie in %.1f .. %.1f deg, median %.1f)\n",
                    offsets.size(), offsets.front(), offsets.back(), offsets[offsets.size() / 2]);
                if (const double slope = leastSquaresLine(followed.turn_label, followed.turn_yaw).slope; std::isfinite(slope))
                    std::printf(
                        "the tracker's yaw turns %.3f deg per degree of poses.csv's within each clip"
                        " (least squares over the frames followed)\n",
                        slope);
            }
        }
    }
    if (pointsOut.is_open()) std::printf("points: %s\n", args.get("--points-out").c_str());
    if (args.has("--plot")) {
        writeCedPlot(args.get("--plot"), curves, maxError, "CED, " + (args.has("--split") ? args.get("--split") + " split" : dir));
        std::printf("CED plot: %s\n", args.get("--plot").c_str());
    }
    return 0;
}

}  // namespace facetrack::cli
