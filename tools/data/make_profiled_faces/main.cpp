// make_profiled_faces: a large-pose set of annotated faces made by face
// profiling (profile/face_profiling.hpp, as 300W-LP was made for 3DDFA), for
// the landmark refiner's training (the train split) and the large-pose
// evaluation (the validation split, never trained on).
//
//   build/tools/make_profiled_faces --split train|validation|test --out DIR [--copies 3]
//                                   [--labels build/dense_labels] [--faces300w DIR] [--seed 23]
//
// Each 300-W crop of the split is turned further the way it looks, `copies`
// tries to |yaw| in [max(|yaw| + 10, 25), 85] deg, by its dense label (the
// face model fitted to MediaPipe's mesh: a teacher label, not ground truth).
// Its annotated 68 points are carried to each copy (profile::carriedLandmarks:
// the jaw follows the turned silhouette). Writes DIR/<crop path>@<n>_yaw<+deg>.pgm
// (grey, binary PGM: load_faces.py reads it without a decoder) with a .pts beside each, DIR/poses.csv (image, yaw_deg: the copy's
// label) for `facetrack eval-landmarks DIR`'s figures by yaw, and DIR/index.csv
// in the layout of ../shared/data/faces300w/index.csv (split and image
// columns) for train_refine's load_faces.py.
//
// With --turn-clips N it writes head turns instead (profile::turnSequence):
// N crops of the split photographed turned 15 deg or more (a frontal face
// turned far shows mostly inpainted holes), evenly spaced through it, each
// turned `--turn-step` deg a frame (2: 60 deg/s at 30 fps) out to at most
// 80 deg and back, and the other way as far as it stays 85 % seen, as
// DIR/<crop>/NNNN.pgm with .pts and poses.csv, for `facetrack eval-landmarks
// DIR --sequences`: tracking through a turn.

#include "app/args.hpp"
#include "app/tool_main.hpp"
#include "common/faces300w.hpp"
#include "core/pts.hpp"
#include "data/dense/label_table.hpp"
#include "data/profile/face_profiling.hpp"
#include "expression/face_warp.hpp"
#include "expression/landmark_net.hpp"
#include "facetrack/face_model.hpp"
#include "model/internals.hpp"

#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

using namespace facetrack;
namespace fs = std::filesystem;

namespace {

const char* kUsage =
    "usage: make_profiled_faces --split train|validation|test --out DIR [--copies 3] [--labels build/dense_labels]\n"
    "                           [--faces300w DIR] [--seed 23] [--turn-clips N [--turn-step 2]]";

int run(int argc, char** argv) {
    const tools::Args args(std::vector<std::string>(argv + 1, argv + argc),
                           {"--split", "--out", "--copies", "--labels", "--faces300w", "--seed", "--turn-clips", "--turn-step"},
                           {"--help"});
    if (args.has("--help")) {
        std::puts(kUsage);
        return 0;
    }
    if (!args.has("--split") || !args.has("--out")) throw Error(std::string("--split and --out are needed\n") + kUsage);
    const std::string split = args.get("--split"), out = args.get("--out");
    tools::parseSplit(split);
    const int copies = args.integer("--copies", 3);
    if (copies < 1 || copies > 20) throw Error("--copies must be in 1..20");
    const int turnClips = args.integer("--turn-clips", 0);
    if (turnClips < 0 || turnClips > 1000) throw Error("--turn-clips must be in 0..1000");
    const bool turns = turnClips > 0;
    const double turnStep = args.number("--turn-step", 2.0);
    if (!(turnStep >= 0.5 && turnStep <= 20.0)) throw Error("--turn-step must be in [0.5, 20] degrees");
    const std::string root = tools::faces300wRoot(args.get("--faces300w", ""));

    const auto model = FaceModel::loadDefault();
    const auto table = dense::readLabelTable(args.get("--labels", "build/dense_labels") + "/faces300w.csv");
    // Every expression the labels have (the dense fit leaves out those the mesh does not show: the gaze).
    std::vector<int> expressions;
    std::vector<std::string> names;
    for (std::size_t k = 0; k < model->expressionNames().size(); ++k) {
        if (table.column(model->expressionNames()[k]) < 0) continue;
        expressions.push_back(static_cast<int>(k));
        names.push_back(model->expressionNames()[k]);
    }
    const dense::LabelColumns columns = dense::labelColumns(table, names);
    // The patch size only scales the carried displacements in and out again.
    const expression::WarpLayout layout = expression::makeWarpLayout(model::dataOf(*model), expressions);
    const fit::FitBasis basis = expression::landmarkBasis(*model, expressions);

    // The crops to turn: all of the split, or with --turn-clips that many turned ones, evenly spaced.
    std::vector<const dense::LabelTable::Row*> rows;
    for (const auto& row : table.rows) {
        if (row.split != split) continue;
        if (turns && std::abs(fit::eulerDegrees(dense::labelParams(columns, row).omega()).y()) < 15.0) continue;
        rows.push_back(&row);
    }
    if (turns && static_cast<int>(rows.size()) > turnClips) {
        std::vector<const dense::LabelTable::Row*> spaced;
        for (int k = 0; k < turnClips; ++k)
            spaced.push_back(rows[rows.size() * static_cast<std::size_t>(k) / static_cast<std::size_t>(turnClips)]);
        rows = spaced;
    }

    fs::create_directories(out);
    std::ofstream poses(out + "/poses.csv"), index;
    poses << "image,yaw_deg\n";
    if (!turns) {
        index.open(out + "/index.csv");
        index << "subset,split,image,pts\n";
    }
    std::mt19937 rng(static_cast<std::mt19937::result_type>(args.integer("--seed", 23)));
    int crops = 0, written = 0;
    const auto total = rows.size();
    for (const dense::LabelTable::Row* labelled : rows) {
        const auto& row = *labelled;
        const cv::Mat grey = cv::imread(root + "/" + row.key, cv::IMREAD_GRAYSCALE);
        if (grey.empty()) throw Error("cannot read " + root + "/" + row.key);
        const std::string stem = row.key.substr(0, row.key.rfind('.'));
        const fit::Landmarks2d points = core::readPts(root + "/" + stem + ".pts").cast<double>();
        const core::Camera camera = core::cameraFor(grey.cols, grey.rows, 60.0, 0.0);
        const fit::FaceParams label = dense::labelParams(columns, row);
        const Eigen::VectorXd identity = dense::labelIdentity(columns, row);
        const std::vector<float> identityF(identity.data(), identity.data() + identity.size());
        const std::vector<float> expression = profile::nativeWeights(*model, expressions, label.expression);
        int kept = 0;  // numbers the copies: two may round to one yaw
        for (const auto& copy : turns ? profile::turnSequence(*model, grey, camera, identityF, expression, label, turnStep)
                                      : profile::profiledCopies(*model, grey, camera, identityF, expression, label, copies, rng)) {
            const double yaw = fit::eulerDegrees(copy.label.omega()).y();
            char suffix[32];
            if (turns) std::snprintf(suffix, sizeof suffix, "/%04d", kept++);
            else std::snprintf(suffix, sizeof suffix, "@%d_yaw%+.0f", kept++, yaw);
            const std::string name = stem + suffix;
            fs::create_directories(fs::path(out + "/" + name).parent_path());
            if (!cv::imwrite(out + "/" + name + ".pgm", copy.image)) throw Error("cannot write " + out + "/" + name + ".pgm");
            core::writePts(out + "/" + name + ".pts",
                           profile::carriedLandmarks(layout, basis, identity, camera, label, points, copy.label).cast<float>());
            poses << name << ".pgm," << yaw << '\n';
            if (index.is_open()) index << stem.substr(0, stem.rfind('/')) << ',' << split << ',' << name << ".pgm," << name << ".pts\n";
            ++written;
        }
        if (++crops % 20 == 0 || turns || static_cast<std::size_t>(crops) == total)
            std::fprintf(stderr, "\r%d/%zu crops, %d %s", crops, total, written, turns ? "frames" : "copies");
    }
    std::fputc('\n', stderr);
    if (crops == 0) throw Error("no labelled crops in split '" + split + "'");
    if (!poses || (index.is_open() && !index)) throw Error("cannot write " + out + "/poses.csv or index.csv");
    std::printf("%d %s crops -> %d %s in %s\n", crops, split.c_str(), written, turns ? "frames of head turns" : "profiled copies",
                out.c_str());
    return 0;
}

}  // namespace

int main(int argc, char** argv) { return tools::runTool("make_profiled_faces", run, argc, argv); }
