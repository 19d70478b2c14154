// turn_scale: how far the landmark fit's yaw turns per degree of a known turn (docs/fitting.md, "Turns").
//
//   build/tools/turn_scale [--profiled build/profiled/validation] [--labels build/dense_labels] [--faces300w DIR]
//   build/tools/turn_scale --photographs train|validation|test [--faces300w DIR]
//
// Face profiling's copies (make_profiled_faces) turn a photographed head by a known angle: a copy's
// yaw in DIR/poses.csv minus its photograph's dense label's (MediaPipe's mesh fitted with the face
// model: a teacher label, not ground truth; the turn itself is exact, the mesh is turned by it).
// Each copy's .pts is its photograph's annotation carried by the turned mesh. Per copy, the fit
// (cold, as a still image is fitted) of the copy's points and of its photograph's; printed per fit
// variant, the least-squares slope of the yaw's change on the turn (1: the fit turns as far) and
// the spread about it:
//   shipped        the face model with the learned convention and prior, the mean identity
//   own identity   the photograph's label identity, the mesh that turned the copy
//   no convention  the face model's own landmark vertices
//   no jaw sides   the 12 jaw points beside the chin (0-5, 11-16) observed where the fit puts
//                  them, refitted until they stay: they pull nothing
//
// With --photographs SPLIT, the 300-W crops of the split instead: the shipped fit's yaw over the
// yaw of the fit without the jaw's sides (the inner points'), by |yaw| of the latter: where the
// jaw's pull turns a photographed head (docs/fitting.md, "Turns"). No label needed.

#include "app/args.hpp"
#include "app/tool_main.hpp"
#include "cli/stats.hpp"
#include "common/faces300w.hpp"
#include "core/pts.hpp"
#include "data/dense/label_table.hpp"
#include "facetrack/face_model.hpp"
#include "fit/face_fitter.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>

using namespace facetrack;

namespace {

struct Variant {
    const char* name;
    std::shared_ptr<const FaceModel> model;
    bool own_identity = false, jaw_sides_free = false;
};

/// The yaw (deg) of the cold fit of `points`.
double fittedYaw(const Variant& v, const core::Camera& camera, const fit::Landmarks2d& points, const Eigen::VectorXd& identity) {
    fit::FaceFitter fitter(fit::basisOf(v.model), {});
    if (v.own_identity) fitter.setIdentity(identity.head(std::min<Eigen::Index>(identity.size(), fit::basisOf(v.model)->identityCount())));
    fit::FaceParams p;
    fit::Landmarks2d observed = points;
    fit::FitReport report = fitter.fit(camera, observed, p, false);
    for (int round = 0; v.jaw_sides_free && round < 10; ++round) {
        for (int i = 0; i < 17; ++i)
            if (i < 6 || i > 10) observed.col(i) = report.projected.col(i);
        p = fit::FaceParams();
        report = fitter.fit(camera, observed, p, false);
    }
    return fit::eulerDegrees(p.omega()).y();
}

/// The shipped fit's yaw against the inner points' on the annotated crops of a 300-W split, by |yaw|.
int photographs(const std::string& root, const std::string& split) {
    const auto model = FaceModel::loadDefault();
    const Variant shipped{"shipped", model}, inner{"no jaw sides", model, false, true};
    struct Bin {
        double from, to, full = 0.0, inner = 0.0;
        std::vector<double> differences = {};
    };
    std::vector<Bin> bins = {{0, 10}, {10, 20}, {20, 30}, {30, 90}};
    int faces = 0;
    for (const auto& image : tools::list300W(root, tools::parseSplit(split))) {
        const cv::Mat grey = cv::imread(image.image, cv::IMREAD_GRAYSCALE);
        if (grey.empty()) throw Error("cannot read " + image.image);
        const fit::Landmarks2d points = core::readPts(image.pts).cast<double>();
        const core::Camera camera = core::cameraFor(grey.cols, grey.rows, 60.0, 0.0);
        const double yawInner = std::abs(fittedYaw(inner, camera, points, {})), yawFull = std::abs(fittedYaw(shipped, camera, points, {}));
        for (Bin& bin : bins) {
            if (yawInner < bin.from || yawInner >= bin.to) continue;
            bin.full += yawFull;
            bin.inner += yawInner;
            bin.differences.push_back(yawFull - yawInner);
        }
        if (++faces % 100 == 0) std::fprintf(stderr, "\r%d faces", faces);
    }
    std::fprintf(stderr, "\r");
    std::printf("%d %s crops: |yaw| of the shipped fit against that of the fit without the jaw's sides (the inner points'):\n", faces,
                split.c_str());
    for (Bin& bin : bins) {
        if (bin.differences.empty()) continue;
        std::nth_element(bin.differences.begin(), bin.differences.begin() + static_cast<std::ptrdiff_t>(bin.differences.size() / 2),
                         bin.differences.end());
        std::printf("  inner |yaw| %2.0f-%2.0f deg: %4zu faces, mean ratio %.3f, median difference %+.2f deg\n", bin.from, bin.to,
                    bin.differences.size(), bin.full / bin.inner, bin.differences[bin.differences.size() / 2]);
    }
    return 0;
}

int run(int argc, char** argv) {
    const tools::Args args(std::vector<std::string>(argv + 1, argv + argc), {"--profiled", "--labels", "--faces300w", "--photographs"},
                           {"--help"});
    if (args.has("--help")) {
        std::puts(
            "usage: turn_scale [--profiled build/profiled/validation] [--labels build/dense_labels] [--faces300w DIR]\n"
            "       turn_scale --photographs train|validation|test [--faces300w DIR]");
        return 0;
    }
    const std::string root = tools::faces300wRoot(args.get("--faces300w", ""));
    if (args.has("--photographs")) return photographs(root, args.get("--photographs"));
    const std::string profiled = args.get("--profiled", "build/profiled/validation");
    const dense::LabelTable table = dense::readLabelTable(args.get("--labels", "build/dense_labels") + "/faces300w.csv");
    const dense::LabelColumns columns = dense::labelColumns(table, {});
    const int yawColumn = table.column("yaw_deg");
    if (yawColumn < 0) throw Error("the labels have no yaw_deg column");
    std::map<std::string, const dense::LabelTable::Row*> byStem;  // the photograph's key without its extension
    for (const auto& row : table.rows) byStem[row.key.substr(0, row.key.rfind('.'))] = &row;

    const auto withConvention = FaceModel::loadDefault();
    const auto bare = FaceModel::load(withConvention->sourcePath());
    const std::vector<Variant> variants = {{"shipped", withConvention},
                                           {"own identity", withConvention, true},
                                           {"no convention", bare},
                                           {"no jaw sides", withConvention, false, true}};
    std::vector<double> turns;                                  // per copy, its known turn (deg)
    std::vector<std::vector<double>> changes(variants.size());  // per variant and copy, the fitted yaw's change
    std::map<std::string, std::vector<double>> photographYaw;   // per photograph, per variant

    std::ifstream poses(profiled + "/poses.csv");
    if (!poses) throw Error("cannot read " + profiled + "/poses.csv (make_profiled_faces writes it)");
    std::string line;
    std::getline(poses, line);
    int copies = 0, skipped = 0;
    const auto load = [](const std::string& image, cv::Mat& grey, fit::Landmarks2d& points) {
        grey = cv::imread(image, cv::IMREAD_GRAYSCALE);
        if (grey.empty()) throw Error("cannot read " + image);
        const core::Shape2 pts = core::readPts(image.substr(0, image.rfind('.')) + ".pts");
        if (pts.cols() != 68) throw Error(image + ": its .pts does not have 68 points");
        points = pts.cast<double>();
    };
    while (std::getline(poses, line)) {
        const auto comma = line.find(',');
        const std::string copy = line.substr(0, comma);
        const double copyYaw = std::stod(line.substr(comma + 1));
        const std::string stem = copy.substr(0, copy.find('@'));
        const auto label = byStem.find(stem);
        if (label == byStem.end()) {
            ++skipped;
            continue;
        }
        const Eigen::VectorXd identity = dense::labelIdentity(columns, *label->second);
        cv::Mat grey;
        fit::Landmarks2d points;
        if (!photographYaw.count(stem)) {
            load(root + "/" + label->second->key, grey, points);
            const core::Camera camera = core::cameraFor(grey.cols, grey.rows, 60.0, 0.0);
            for (const Variant& v : variants) photographYaw[stem].push_back(fittedYaw(v, camera, points, identity));
        }
        load(profiled + "/" + copy, grey, points);
        const core::Camera camera = core::cameraFor(grey.cols, grey.rows, 60.0, 0.0);
        turns.push_back(copyYaw - label->second->values[static_cast<std::size_t>(yawColumn)]);
        for (std::size_t k = 0; k < variants.size(); ++k)
            changes[k].push_back(fittedYaw(variants[k], camera, points, identity) - photographYaw[stem][k]);
        if (++copies % 50 == 0) std::fprintf(stderr, "\r%d copies", copies);
    }
    std::fprintf(stderr, "\r");
    if (copies == 0) throw Error("no copy in " + profiled + " has a dense label");
    std::printf("%d copies in %s (%d without a label left out); the fit of their annotated points against the turn:\n", copies,
                profiled.c_str(), skipped);
    for (std::size_t k = 0; k < variants.size(); ++k) {
        const cli::Line line = cli::leastSquaresLine(turns, changes[k]);
        std::printf("  %-14s turns %.3f deg per degree, spread %.2f deg\n", variants[k].name, line.slope, line.spread);
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) { return tools::runTool("turn_scale", run, argc, argv); }
