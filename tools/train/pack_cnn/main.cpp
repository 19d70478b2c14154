// pack_cnn: the CNN cascade's model file (facetrack/cnn_model.hpp) from the
// ONNX exports of tools/train/expression/train_stage.py (docs/cnn.md).
//
//   build/tools/pack_cnn --nets build/cnn/stage1.onnx[,stage2.onnx] --rounds 2[,1] [--landmark-net build/cnn/landmarks.onnx]
//                        [--expressions-only [--neutral-from build/dense_labels/faces300w.csv | --rest-from-validation
//                                             [--gain-from-validation]]
//                                            [--min-validation-r R [--leave-out NAME,...]]]
//                        [--mirror-average] [--corrects-fit]
//                        [--base FILE.ftm]
//                        [--geometry build/cnn/geometry [--lips build/cnn/lips.onnx]]
//                        [--base FILE.ftm --export-net OUT.onnx]
//                        --out build/cnn/cascade.ftm [--provenance "..."]
//
// --base: start from that file's nets (the options given replace theirs; --nets replaces its stage and its
// geometry net, which was chosen against that stage). The refine stage's nets have their own file
// (tools/train/pack_refiner).
//
// --expressions-only: the nets were trained to read expressions (train_stage.py --expressions);
// the stage keeps the fit's pose and the shapes the fit estimates (cnn_model_data.hpp).
// --neutral-from: each expression's neutral w0, the median of its dense label over the file's
// training rows (cnn_model_data.hpp says why). --rest-from-validation: each expression's neutral is
// instead its rest level on the 300-W validation crops, how high the net reads it on faces that do
// not show it (the trainer's OUT.validation_rest.txt beside the last net: the estimate's 0.9
// quantile over the crops whose label is at most the median; a pair's mean), so that a relaxed
// face reads 0 on nine in ten such faces. --min-validation-r: only the expressions whose
// estimate agreed with the labels on the validation data by at least R (Pearson, the mean of a
// left / right pair; the trainer's OUT.validation_r.txt beside the net: the 300-W validation crops,
// or with train_stage.py --teacher the validation people) are reported; --leave-out N,... names
// expressions not reported whatever their r.
// --gain-from-validation (with --rest-from-validation): each expression's full-expression reading
// w1 = w0 + (1 - w0) / g, g its gain on the validation people (the trainer's OUT.validation_gain.txt;
// a pair's mean), so that the stage reports (w - w0) / (w1 - w0) (cnn_model_data.hpp).
// --mirror-average: the stages read each patch and its mirror image and apply the mean update
// (cnn/update_net.hpp, refine), so that a face and its mirror image read alike; twice the nets' time.
// --corrects-fit (with --expressions-only): the stage also corrects the shapes the fit estimates
// (cnn_model_data.hpp).
// --geometry PREFIX (with --nets and --min-validation-r): the geometry net of
// tools/train/expression/train_geometry.py (PREFIX.geometry.txt; expression/geometry_net.hpp). A
// shape is read from it where its r on the validation people's frames (PREFIX.validation_geometry_r.txt,
// a pair's mean) is at least R and above the texture net's on the same frames (the trainer's
// OUT.validation_r_frames.txt), between its rest level there (PREFIX.validation_geometry_rest.txt) and 1.
// --lips NET.onnx (with --geometry): the lip net of tools/train/expression/train_lips.py, whose points
// the geometry net was trained to read (train_geometry.py --lips; expression/lip_net.hpp).
// --export-net OUT.onnx (with --base): writes the base's first stage net and stops (train_stage.py
// --from-onnx computes its validation figures).
//
// Each ONNX file's OUT.columns.txt (written beside it by the trainer) must list
// the update outputs cnn/update_net.hpp defines, with the labelled expressions
// of the dense teacher labels in the face model's names, or for the landmark
// net the 68 displacements of cnn/landmark_net.hpp (l_x0, l_y0, ..., l_y67);
// every net is run once here to check it loads in OpenCV's dnn and gives that
// many outputs.

#include "app/args.hpp"
#include "app/tool_main.hpp"
#include "core/binary_io.hpp"
#include "data/dense/label_table.hpp"
#include "expression/geometry_net.hpp"
#include "expression/landmark_net.hpp"
#include "expression/lip_net.hpp"
#include "expression/update_net.hpp"
#include "facetrack/face_model.hpp"
#include "fit/fit_basis.hpp"
#include "nn/cnn_model_data.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <fstream>
#include <sstream>

using namespace facetrack;

namespace {

std::string readBytes(const std::string& path) { return core::readFileBytes(path, "'" + path + "'"); }

std::string columnsPath(const std::string& onnxPath) {
    return onnxPath.substr(0, onnxPath.size() - std::string(".onnx").size()) + ".columns.txt";
}

std::vector<std::string> columns(const std::string& onnxPath) {
    std::stringstream lines(readBytes(columnsPath(onnxPath)));
    std::vector<std::string> names;
    for (std::string line; std::getline(lines, line);)
        if (!line.empty()) names.push_back(line);
    return names;
}

/// The expression names of a net's columns file: the lines after the six pose outputs.
std::vector<std::string> expressionColumns(const std::string& onnxPath) {
    const std::string path = columnsPath(onnxPath);
    const std::vector<std::string> names = columns(onnxPath);
    const std::vector<std::string> pose = {"omega_x", "omega_y", "omega_z", "centre_x", "centre_y", "centre_z"};
    if (names.size() < pose.size() || !std::equal(pose.begin(), pose.end(), names.begin())) {
        throw Error(path + ": expected the update's six pose outputs (" + pose.front() + " ... " + pose.back() + ") first");
    }
    return {names.begin() + static_cast<std::ptrdiff_t>(pose.size()), names.end()};
}

/// The trainer's OUT.SUFFIX beside the net OUT.onnx.
std::string beside(const std::string& onnxPath, const std::string& suffix) {
    return onnxPath.substr(0, onnxPath.size() - std::string(".onnx").size()) + suffix;
}

/// Per expression, the value a trainer's file gives it (lines "name value"), averaged with its
/// mirror partner's (fit::mirrorName: browDown_L and browDown_R, jawLeft and jawRight) so that a
/// face and its mirror image are treated alike.
std::vector<double> pairAveraged(const std::string& path, const std::vector<std::string>& names) {
    std::stringstream lines(readBytes(path));
    std::map<std::string, double> value;
    std::string name, text;
    while (lines >> name >> text) value[name] = std::stod(text);  // "nan" too: a constant label
    const auto of = [&](const std::string& n) {
        const auto it = value.find(n);
        if (it == value.end()) throw Error(path + " has no " + n);
        return std::isfinite(it->second) ? it->second : 0.0;
    };
    std::vector<double> out;
    for (const auto& n : names) {
        const std::string partner = fit::mirrorName(n);
        out.push_back(0.5 * (of(n) + of(partner.empty() ? n : partner)));
    }
    return out;
}

/// The geometry net of train_geometry.py's PREFIX.geometry.txt, checked against the trainer's own
/// reading of one validation frame written after it.
std::vector<nn::DenseLayer> readGeometryNet(const std::string& prefix, const std::vector<std::string>& expressions) {
    const std::string path = prefix + ".geometry.txt";
    std::stringstream in(readBytes(path));
    std::string header, word;
    std::getline(in, header);
    if (header != "facetrack geometry net 1") throw Error(path + ": not a geometry net of train_geometry.py");
    int count = 0;
    in >> word >> count;
    if (word != "layers" || count < 1 || count > 8) throw Error(path + ": expected 'layers N'");
    std::vector<nn::DenseLayer> layers(static_cast<std::size_t>(count));
    for (nn::DenseLayer& l : layers) {
        in >> l.rows >> l.cols;
        if (!in || l.rows < 1 || l.cols < 1 || l.rows > 4096 || l.cols > 4096) throw Error(path + ": a layer's size");
        l.weight.resize(static_cast<std::size_t>(l.rows) * static_cast<std::size_t>(l.cols));
        l.bias.resize(static_cast<std::size_t>(l.rows));
        for (float& v : l.weight) in >> v;
        for (float& v : l.bias) in >> v;
    }
    Eigen::VectorXf f(layers.front().cols);
    for (float& v : f) in >> v;
    Eigen::VectorXf expected(layers.back().rows);
    for (float& v : expected) in >> v;
    if (!in) throw Error(path + ": truncated");
    if (layers.back().rows != static_cast<int>(expressions.size())) throw Error(path + ": its outputs are not the nets' expressions");
    expression::GeometryNet net(layers, expressions);
    const float error = (net.forward(f) - expected).cwiseAbs().maxCoeff();
    if (!(error < 1e-4f)) throw Error(path + ": the net reads its check frame " + std::to_string(error) + " off the trainer's reading");
    return layers;
}

/// Per name, the median of its column over the table's training rows.
std::vector<float> trainingMedians(const std::string& path, const std::vector<std::string>& names) {
    const dense::LabelTable table = dense::readLabelTable(path);
    const dense::LabelColumns columns = dense::labelColumns(table, names);
    std::vector<float> medians;
    for (const int c : columns.expressions) {
        std::vector<double> values;
        for (const auto& row : table.rows) {
            if (row.split == "train") values.push_back(row.values[static_cast<std::size_t>(c)]);
        }
        if (values.empty()) throw Error(path + ": no training rows");
        std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2), values.end());
        medians.push_back(std::clamp(static_cast<float>(values[values.size() / 2]), 0.f, 0.9f));
    }
    return medians;
}

int run(int argc, char** argv) {
    const tools::Args args(
        std::vector<std::string>(argv + 1, argv + argc),
        {"--nets", "--rounds", "--landmark-net", "--out", "--provenance", "--neutral-from", "--min-validation-r", "--leave-out", "--base",
         "--geometry", "--lips", "--export-net"},
        {"--help", "--expressions-only", "--mirror-average", "--corrects-fit", "--rest-from-validation", "--gain-from-validation"});
    if (args.has("--help") || !(args.has("--nets") || args.has("--base")) || !(args.has("--out") || args.has("--export-net"))) {
        std::puts(
            "usage: pack_cnn --nets A.onnx[,B.onnx] [--rounds 1[,1]] [--landmark-net L.onnx] [--expressions-only] --out FILE.ftm\n"
            "                [--provenance TEXT] [--neutral-from LABELS.csv] [--min-validation-r R [--leave-out N,...]]\n"
            "                [--base FILE.ftm] [--mirror-average] [--corrects-fit] [--rest-from-validation\n"
            "                [--gain-from-validation]] [--geometry PREFIX [--lips NET.onnx]]\n"
            "       pack_cnn --base FILE.ftm --export-net OUT.onnx");
        return args.has("--help") ? 0 : 2;
    }
    if (args.has("--export-net")) {  // the base's first stage net, e.g. for train_stage.py --from-onnx
        if (!args.has("--base")) throw Error("--export-net goes with --base");
        const nn::CnnModelData base = nn::readCnnModel(args.get("--base"));
        std::ofstream(args.get("--export-net"), std::ios::binary) << base.stages.front().onnx;
        std::printf("wrote %s\n", args.get("--export-net").c_str());
        return 0;
    }
    const auto nets = tools::splitList(args.get("--nets", ""));
    auto rounds = tools::splitList(args.get("--rounds", ""));
    if (rounds.empty()) rounds.assign(nets.size(), "1");
    if (rounds.size() != nets.size()) throw Error("--rounds needs one count per net");

    const auto face = FaceModel::loadDefault();
    nn::CnnModelData model;
    if (args.has("--base")) {
        model = nn::readCnnModel(args.get("--base"));
        if (!nets.empty()) {  // a new stage: the base's geometry readings were chosen against its nets
            model.stages.clear();
            model.geometry_net.clear();
            model.geometry_reported.clear();
            model.geometry_neutral.clear();
            model.geometry_full.clear();
            model.lip_net.clear();
        }
    }
    model.provenance = args.get("--provenance", model.provenance);
    model.expressions_only = model.expressions_only || args.has("--expressions-only");
    model.corrects_fit = model.corrects_fit || args.has("--corrects-fit");
    if (model.corrects_fit && !model.expressions_only) throw Error("--corrects-fit goes with --expressions-only");
    for (std::size_t i = 0; i < nets.size(); ++i) {
        const auto names = expressionColumns(nets[i]);
        if (i == 0) model.expressions = names;
        if (names != model.expressions) throw Error(nets[i] + ": its expressions differ from the first net's");
        nn::expressionIndices(face->expressionNames(), names);  // every name is the face model's, or it throws
        nn::CnnStageData stage;
        stage.rounds = std::stoi(rounds[i]);
        stage.onnx = readBytes(nets[i]);
        nn::PatchNet check(stage.onnx, model.patch_size, 6 + static_cast<int>(names.size()), nets[i]);  // loads and runs, or throws
        model.stages.push_back(std::move(stage));
        std::printf("stage %zu: %s, %d round(s), %zu bytes\n", i + 1, nets[i].c_str(), model.stages.back().rounds,
                    model.stages.back().onnx.size());
    }
    if (args.has("--mirror-average")) {
        if (model.stages.empty()) throw Error("--mirror-average needs cascade stages (--nets)");
        expression::updateMirror(model.expressions);  // every sided expression's partner is there, or it throws
        model.mirror_averaged = true;
    }
    if (args.has("--landmark-net")) {
        const std::string path = args.get("--landmark-net");
        std::vector<std::string> expected;
        for (int i = 0; i < model::kLandmarkCount; ++i)
            for (const char* axis : {"l_x", "l_y"}) expected.push_back(axis + std::to_string(i));
        if (columns(path) != expected) throw Error(columnsPath(path) + ": expected the 68 landmark displacements l_x0, l_y0, ..., l_y67");
        model.landmark_net = readBytes(path);
        nn::PatchNet check(model.landmark_net, model.patch_size, expression::kLandmarkOutputs, path);
        std::printf("landmark net: %s, %zu bytes\n", path.c_str(), model.landmark_net.size());
    }
    if (args.has("--neutral-from") && args.has("--rest-from-validation")) throw Error("--neutral-from or --rest-from-validation, not both");
    if (args.has("--neutral-from") || args.has("--rest-from-validation")) {
        if (!model.expressions_only) throw Error("--neutral-from and --rest-from-validation go with --expressions-only");
        model.neutral.clear();
        model.full.clear();  // read between the old neutral and full, or not at all
        if (args.has("--neutral-from")) {
            model.neutral = trainingMedians(args.get("--neutral-from"), model.expressions);
        } else {
            if (nets.empty()) throw Error("--rest-from-validation needs the nets (--nets)");
            for (const double level : pairAveraged(beside(nets.back(), ".validation_rest.txt"), model.expressions))
                model.neutral.push_back(std::clamp(static_cast<float>(level), 0.f, 0.9f));
        }
        for (std::size_t k = 0; k < model.neutral.size(); ++k) {
            if (model.neutral[k] >= 0.05f) std::printf("neutral %s %.3f\n", model.expressions[k].c_str(), model.neutral[k]);
        }
    }
    if (args.has("--gain-from-validation")) {
        if (!args.has("--rest-from-validation")) throw Error("--gain-from-validation goes with --rest-from-validation");
        const std::vector<double> gain = pairAveraged(beside(nets.back(), ".validation_gain.txt"), model.expressions);
        for (std::size_t k = 0; k < model.neutral.size(); ++k) {
            const double g = std::clamp(gain[k], 1.0, 10.0);
            model.full.push_back(static_cast<float>(model.neutral[k] + (1.0 - model.neutral[k]) / g));
            if (g > 1.01) std::printf("gain %s %.2f\n", model.expressions[k].c_str(), g);
        }
    }
    if (args.has("--min-validation-r")) {
        if (!model.expressions_only) throw Error("--min-validation-r goes with --expressions-only");
        const double minimum = args.number("--min-validation-r", 0.5);
        model.reported.clear();
        for (const double r : pairAveraged(beside(nets.back(), ".validation_r.txt"), model.expressions))
            model.reported.push_back(r >= minimum);
        for (const std::string& name : tools::splitList(args.get("--leave-out", ""))) {
            const auto it = std::find(model.expressions.begin(), model.expressions.end(), name);
            if (it == model.expressions.end()) throw Error("--leave-out: the nets have no expression '" + name + "'");
            model.reported[static_cast<std::size_t>(it - model.expressions.begin())] = false;
        }
        std::printf("reported:");
        for (std::size_t k = 0; k < model.reported.size(); ++k) {
            if (model.reported[k]) std::printf(" %s", model.expressions[k].c_str());
        }
        std::printf("\n");
    }
    if (args.has("--geometry")) {
        if (!args.has("--min-validation-r") || nets.empty()) throw Error("--geometry goes with --nets and --min-validation-r");
        const std::string prefix = args.get("--geometry");
        model.geometry_net = readGeometryNet(prefix, model.expressions);
        model.lip_net.clear();
        if (args.has("--lips")) {
            model.lip_net = readBytes(args.get("--lips"));
            expression::LipNet check(model.lip_net, model.lip_patch_size, model.lip_patch_half, args.get("--lips"));  // loads, or throws
        }
        if ((model.geometry_net.front().cols != nn::kGeometryFeatures) != !model.lip_net.empty())
            throw Error(prefix + ".geometry.txt: " +
                        (model.lip_net.empty() ? "the net reads the lips: give --lips" : "the net does not read the lips"));
        // on the same frames as the geometry net's: the validation people's, without the warped copies
        const auto texture_r = pairAveraged(beside(nets.back(), ".validation_r_frames.txt"), model.expressions);
        const auto geometry_r = pairAveraged(prefix + ".validation_geometry_r.txt", model.expressions);
        const auto geometry_rest = pairAveraged(prefix + ".validation_geometry_rest.txt", model.expressions);
        const double minimum = args.number("--min-validation-r", 0.5);
        const auto leftOut = tools::splitList(args.get("--leave-out", ""));
        std::printf("read from the geometry:");
        for (std::size_t k = 0; k < model.expressions.size(); ++k) {
            const std::string& n = model.expressions[k];
            const bool kept = geometry_r[k] >= minimum && geometry_r[k] > texture_r[k] &&
                              std::find(leftOut.begin(), leftOut.end(), n) == leftOut.end();
            model.geometry_reported.push_back(kept);
            model.geometry_neutral.push_back(std::clamp(static_cast<float>(geometry_rest[k]), 0.f, 0.9f));
            model.geometry_full.push_back(1.f);  // no gain: train_geometry.py says why
            if (kept) std::printf(" %s (r %.2f against %.2f)", n.c_str(), geometry_r[k], texture_r[k]);
        }
        std::printf("\n");
    }
    nn::writeCnnModel(args.get("--out"), model);
    std::printf("wrote %s (%zu expressions)\n", args.get("--out").c_str(), model.expressions.size());
    return 0;
}

}  // namespace

int main(int argc, char** argv) { return tools::runTool("pack_cnn", run, argc, argv); }
