// eval_cnn: the CNN cascade's robustness figure (issue 17). For every 300-W
// crop of a split (validation by default; never a training crop), starts
// perturbed from its dense teacher label (MediaPipe's mesh fitted with the
// face model: a teacher label, not ground truth) by yaw +-Y deg and scale
// +-D (uniform; the target: +-15 deg, +-10 %), then K rounds of the
// cascade (cnn/update_net.hpp). Reports per round the rotation error
// (the angle of R_est R_label^T), the depth error, the expression error and
// the share of starts within 3 deg of the label.
//
//   build/tools/eval_cnn --nets build/cnn/stage1.onnx[,stage2.onnx] [--iterations 3] [--starts 5]
//                        [--split validation] [--yaw-deg 15] [--depth 0.1] [--labels build/dense_labels]
//
// Round i runs net min(i, count - 1): a list of stages, the last one repeated.

#include "app/args.hpp"
#include "app/tool_main.hpp"
#include "cnn/update_net.hpp"
#include "common/faces300w.hpp"
#include "dense/dense_fit.hpp"
#include "dense/label_table.hpp"
#include "facetrack/face_model.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <random>
#include <sstream>

using namespace facetrack;

namespace {

double rotationErrorDeg(const fit::FaceParams& a, const fit::FaceParams& b) {
    return Eigen::AngleAxisd(fit::rotationOf(a.omega()) * fit::rotationOf(b.omega()).transpose()).angle() * 180.0 / M_PI;
}

struct RoundErrors {
    std::vector<double> rotation_deg, depth_pct, expression;
};

void report(const char* name, RoundErrors e) {
    const auto mean = [](const std::vector<double>& v) {
        double s = 0;
        for (double x : v) s += x;
        return v.empty() ? 0.0 : s / static_cast<double>(v.size());
    };
    const double within = static_cast<double>(std::count_if(e.rotation_deg.begin(), e.rotation_deg.end(), [](double x) { return x < 3.0; }));
    std::nth_element(e.rotation_deg.begin(), e.rotation_deg.begin() + static_cast<std::ptrdiff_t>(e.rotation_deg.size() / 2), e.rotation_deg.end());
    std::printf("%-8s rotation mean %5.2f median %5.2f deg, within 3 deg %5.1f %%; depth %5.2f %%; expression MAE %.4f\n", name,
                mean(e.rotation_deg), e.rotation_deg[e.rotation_deg.size() / 2], 100.0 * within / static_cast<double>(e.rotation_deg.size()),
                mean(e.depth_pct), mean(e.expression));
}

int run(int argc, char** argv) {
    const tools::Args args(std::vector<std::string>(argv + 1, argv + argc),
                           {"--nets", "--iterations", "--starts", "--split", "--yaw-deg", "--depth", "--labels", "--faces300w"}, {"--help"});
    if (args.has("--help") || !args.has("--nets")) {
        std::puts("usage: eval_cnn --nets A.onnx[,B.onnx] [--iterations 3] [--starts 5] [--split validation]\n"
                  "       [--yaw-deg 15] [--depth 0.1] [--labels build/dense_labels] [--faces300w DIR]");
        return args.has("--help") ? 0 : 2;
    }
    const std::string split = args.get("--split", "validation");
    if (split == "train") throw Error("eval_cnn measures held-out crops: --split validation or test");
    const int iterations = static_cast<int>(args.number("--iterations", 3));
    const int starts = static_cast<int>(args.number("--starts", 5));
    const double yawDeg = args.number("--yaw-deg", 15.0), depth = args.number("--depth", 0.10);
    if (iterations < 1 || starts < 1) throw Error("--iterations and --starts must be at least 1");

    const auto model = FaceModel::load(FaceModel::defaultPath());
    const cnn::WarpLayout layout = cnn::makeWarpLayout(model->data(), dense::labelledExpressions(model->data()));
    const int expressions = static_cast<int>(layout.anchors.expressions.size());
    std::vector<std::unique_ptr<cnn::UpdateNet>> nets;
    std::stringstream list(args.get("--nets"));
    for (std::string path; std::getline(list, path, ',');) nets.push_back(std::make_unique<cnn::UpdateNet>(path, layout.size, expressions));

    const auto table = dense::readLabelTable(args.get("--labels", "build/dense_labels") + "/faces300w.csv");
    const dense::LabelColumns columns = dense::labelColumns(table, layout.anchors.expressionNames(model->data()));
    const std::string root = tools::faces300wRoot(args.get("--faces300w", ""));
    std::mt19937 rng(23);
    std::uniform_real_distribution<double> sym(-1.0, 1.0);
    std::vector<RoundErrors> rounds(static_cast<std::size_t>(iterations + 1));
    cv::Mat patch;
    int crops = 0;
    for (const auto& row : table.rows) {
        if (row.split != split) continue;
        const cv::Mat grey = cv::imread(root + "/" + row.key, cv::IMREAD_GRAYSCALE);
        if (grey.empty()) throw Error("cannot read " + root + "/" + row.key);
        const fit::Camera camera = fit::cameraFor(grey.cols, grey.rows, 60.0, 0.0);
        const fit::FaceParams label = dense::labelParams(columns, row);
        const Eigen::VectorXd identity = dense::labelIdentity(columns, row);
        for (int s = 0; s < starts; ++s) {
            fit::FaceParams params = label;  // turned about the face centre and scaled
            Eigen::VectorXd move = Eigen::VectorXd::Zero(6);
            move[1] = yawDeg * M_PI / 180.0 * sym(rng);
            const Eigen::Vector3d centre = fit::rotationOf(label.omega()) * layout.centre + label.translation();
            move.segment<3>(3) = depth * sym(rng) * centre / centre.z();
            cnn::applyUpdate(layout, move, params);
            for (int i = 0; i <= iterations; ++i) {
                if (i > 0) cnn::refine(layout, *nets[static_cast<std::size_t>(std::min<int>(i - 1, static_cast<int>(nets.size()) - 1))], grey, camera, identity, params, 1, patch);
                RoundErrors& e = rounds[static_cast<std::size_t>(i)];
                e.rotation_deg.push_back(rotationErrorDeg(params, label));
                e.depth_pct.push_back(100.0 * std::abs(params.pose[5] - label.pose[5]) / label.pose[5]);
                e.expression.push_back((params.expression - label.expression).cwiseAbs().mean());
            }
        }
        if (++crops % 20 == 0) std::fprintf(stderr, "\r%d crops", crops);
    }
    if (crops == 0) throw Error("no crops in split '" + split + "'");
    std::fprintf(stderr, "\r");
    std::printf("%d %s crops x %d starts (yaw +-%.0f deg, scale +-%.0f %%), against the dense teacher labels:\n", crops, split.c_str(), starts,
                yawDeg, 100.0 * depth);
    for (int i = 0; i <= iterations; ++i) report(i == 0 ? "start" : ("round " + std::to_string(i)).c_str(), rounds[static_cast<std::size_t>(i)]);
    return 0;
}

}  // namespace

int main(int argc, char** argv) { return tools::runTool("eval_cnn", run, argc, argv); }
