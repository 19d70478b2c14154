// train_landmarks: trains the LBF landmark model on the 300-W training split.
//
//   train_landmarks [--data ../shared/data/faces300w] [--out models/landmarks_lbf.ftm]
//                   [--stages 7] [--trees 4] [--depth 5] [--inits 6] [--threads 2] [--seed 1] [--ridge 15000]
//                   [--hull-padding 0.1] [--resume]
//
// Long: run it under nohup (docs/landmarks.md). After each stage it writes
// OUT.partial; --resume continues from there. Deterministic for a given seed.

#include "app/args.hpp"
#include "app/tool_main.hpp"
#include "common/faces300w.hpp"
#include "core/environment.hpp"
#include "core/image.hpp"
#include "core/pts.hpp"
#include "core/shape2d.hpp"
#include "facetrack/detector.hpp"
#include "facetrack/version.hpp"
#include "landmarks/lbf.hpp"
#include "landmarks/lbf_trainer.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <atomic>
#include <mutex>
#include <optional>
#include <random>
#include <thread>

namespace fs = std::filesystem;

namespace facetrack::tools {
namespace {

using core::Shape68;

const auto kStart = std::chrono::steady_clock::now();

double elapsedSeconds() { return std::chrono::duration<double>(std::chrono::steady_clock::now() - kStart).count(); }

void logLine(const std::string& line) {
    std::printf("[%7.1fs] %s\n", elapsedSeconds(), line.c_str());
    std::fflush(stdout);
}

/// Redraws only when the percentage or the label changes.
void progressBar(const std::string& label, double done) {
    static std::string lastLabel;
    static int lastPercent = -1;
    const int percent = static_cast<int>(done * 100 + 0.5);
    if (label == lastLabel && percent == lastPercent) return;
    lastLabel = label;
    lastPercent = percent;
    const int width = 30, filled = static_cast<int>(done * width + 0.5);
    std::fprintf(stderr, "\r[%s%s] %3d%% %-40s", std::string(filled, '#').c_str(), std::string(width - filled, ' ').c_str(), percent,
                 label.c_str());
    if (done >= 1.0) std::fputc('\n', stderr);
    std::fflush(stderr);
}

/// One training picture: a 300-W crop, mirrored or not, rotated and scaled or not.
struct Variant {
    cv::Mat bgr;
    Shape68 truth;
    bool original = false;  ///< unmirrored, unrotated: the cascade's box prior is measured on these
};

Shape68 toShape68(const core::Shape2& s) {
    if (s.cols() != core::kLandmarks) throw Error("expected 68 points");
    return s;
}

std::vector<Variant> makeVariants(const cv::Mat& bgr, const Shape68& truth, std::mt19937_64& rng) {
    cv::Mat mirrored;
    cv::flip(bgr, mirrored, 1);
    Shape68 mirroredTruth;
    for (int i = 0; i < core::kLandmarks; ++i) {
        mirroredTruth.col(kMirror68[i]) = Eigen::Vector2f(bgr.cols - 1 - truth(0, i), truth(1, i));
    }
    std::vector<Variant> out = {{bgr, truth, true}, {mirrored, mirroredTruth, false}};
    // Small rotations and scales (about the crop centre) of both.
    std::normal_distribution<float> angle(0.f, 10.f);
    std::uniform_real_distribution<float> scale(0.9f, 1.1f);
    for (int k = 0; k < 2; ++k) {
        const cv::Mat m = cv::getRotationMatrix2D(cv::Point2f((bgr.cols - 1) / 2.f, (bgr.rows - 1) / 2.f),
                                                  std::clamp(angle(rng), -25.f, 25.f), scale(rng));
        Variant v;
        cv::warpAffine(out[k].bgr, v.bgr, m, bgr.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
        Eigen::Matrix<float, 2, 3> a;
        for (int r = 0; r < 2; ++r) {
            for (int c = 0; c < 3; ++c) a(r, c) = static_cast<float>(m.at<double>(r, c));
        }
        v.truth = (a.leftCols<2>() * out[k].truth).colwise() + a.col(2);
        out.push_back(std::move(v));
    }
    return out;
}

/// A shape in box coordinates ((0,0) top-left, (1,1) bottom-right).
Shape68 inBox(const Shape68& s, const Box& b) {
    Shape68 out;
    out.row(0) = (s.row(0).array() - b.x0) / b.width();
    out.row(1) = (s.row(1).array() - b.y0) / b.height();
    return out;
}

Shape68 onBox(const Shape68& unit, const Box& b) {
    Shape68 out;
    out.row(0) = unit.row(0).array() * b.width() + b.x0;
    out.row(1) = unit.row(1).array() * b.height() + b.y0;
    return out;
}

/// The box that would place `prior` best onto `truth` (per-axis least squares):
/// used when the detector missed the face.
Box impliedBox(const Shape68& prior, const Shape68& truth) {
    Box b;
    for (int axis = 0; axis < 2; ++axis) {
        const Eigen::ArrayXf p = prior.row(axis).transpose().array() - prior.row(axis).mean();
        const Eigen::ArrayXf t = truth.row(axis).transpose().array() - truth.row(axis).mean();
        const float size = (p * t).sum() / (p * p).sum();
        const float origin = truth.row(axis).mean() - size * prior.row(axis).mean();
        (axis == 0 ? b.x0 : b.y0) = origin;
        (axis == 0 ? b.x1 : b.y1) = origin + size;
    }
    return b;
}

Box jitter(const Box& b, float shift, float scale, std::mt19937_64& rng) {
    std::normal_distribution<float> n(0.f, 1.f);
    const float s = 1.f + scale * n(rng), w = b.width() * s, h = b.height() * s;
    const float cx = (b.x0 + b.x1) / 2 + shift * b.width() * n(rng), cy = (b.y0 + b.y1) / 2 + shift * b.height() * n(rng);
    return {cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2};
}

int run(int argc, char** argv) {
    const Args args(std::vector<std::string>(argv + 1, argv + argc),
                    {"--data", "--out", "--stages", "--trees", "--depth", "--inits", "--threads", "--seed", "--ridge", "--hull-padding"},
                    {"--resume", "--help"});
    if (args.has("--help")) {
        std::puts(
            "usage: train_landmarks [--data DIR] [--out FILE] [--stages 7] [--trees 4] [--depth 5] [--inits 6]\n"
            "                       [--threads 2] [--seed 1] [--ridge 15000] [--hull-padding 0.1] [--resume]");
        return 0;
    }
    setLogHandler({});
    const std::string data = faces300wRoot(args.get("--data"));
    const std::string out = args.get("--out", "models/landmarks_lbf.ftm");
    landmarks::LbfTrainingOptions o;
    o.stages = args.integer("--stages", o.stages);
    o.trees_per_landmark = args.integer("--trees", o.trees_per_landmark);
    o.tree_depth = args.integer("--depth", o.tree_depth);
    o.threads = args.integer("--threads", o.threads);
    o.seed = static_cast<std::uint64_t>(args.integer("--seed", 1));
    o.ridge = static_cast<float>(args.number("--ridge", o.ridge));
    o.hull_padding = static_cast<float>(args.number("--hull-padding", o.hull_padding));
    if (!(o.hull_padding >= 0.f && o.hull_padding < 1.f)) throw Error("--hull-padding must be in [0, 1)");  // the model file's bound
    o.progress = progressBar;
    const int inits = args.integer("--inits", 6);

    // Images and their variants.
    const auto train = list300W(data, Split::Train);
    logLine("training images: " + std::to_string(train.size()) + " (validation and test held out)");
    std::mt19937_64 rng(o.seed);
    std::vector<Variant> variants;
    for (std::size_t i = 0; i < train.size(); ++i) {
        const cv::Mat bgr = cv::imread(train[i].image, cv::IMREAD_COLOR);
        if (bgr.empty()) throw Error("cannot read '" + train[i].image + "'");
        for (auto& v : makeVariants(bgr, toShape68(core::readPts(train[i].pts)), rng)) variants.push_back(std::move(v));
        progressBar("loading and augmenting", double(i + 1) / train.size());
    }

    // Detector boxes: YuNet on every variant, the cascade on the originals.
    std::vector<std::optional<Box>> yunetBoxes(variants.size()), cascadeBoxes(variants.size());
    {
        std::vector<std::unique_ptr<FaceDetector>> yunet, cascade;
        DetectorConfig yc, cc;
        yc.kind = DetectorKind::YuNet;
        cc.kind = DetectorKind::Cascade;
        for (int t = 0; t < std::max(1, o.threads); ++t) {
            yunet.push_back(createFaceDetector(yc));
            cascade.push_back(createFaceDetector(cc));
        }
        std::atomic<int> next{0}, done{0};
        std::mutex progressMutex;
        auto worker = [&](int t) {
            for (int i = next++; i < static_cast<int>(variants.size()); i = next++) {
                const auto& v = variants[i];
                yunetBoxes[i] = matchingBox(yunet[t]->detect(core::viewOf(v.bgr)), core::Shape2(v.truth));
                if (v.original) cascadeBoxes[i] = matchingBox(cascade[t]->detect(core::viewOf(v.bgr)), core::Shape2(v.truth));
                std::lock_guard<std::mutex> lock(progressMutex);
                progressBar("detecting faces", double(++done) / variants.size());
            }
        };
        std::vector<std::thread> threads;
        for (int t = 1; t < std::max(1, o.threads); ++t) threads.emplace_back(worker, t);
        worker(0);
        for (auto& t : threads) t.join();
    }

    std::vector<landmarks::TrainingImage> images;
    for (auto& v : variants) {
        landmarks::TrainingImage im;
        cv::cvtColor(v.bgr, im.gray, cv::COLOR_BGR2GRAY);
        im.truth = v.truth;
        images.push_back(std::move(im));
        v.bgr.release();
    }

    landmarks::LbfModel model = landmarks::prepareLbfModel(images, o);
    for (const auto& [name, boxes] : {std::pair{"yunet", &yunetBoxes}, std::pair{"cascade", &cascadeBoxes}}) {
        Shape68 sum = Shape68::Zero();
        int count = 0;
        for (std::size_t i = 0; i < images.size(); ++i) {
            if ((*boxes)[i]) {
                sum += inBox(images[i].truth, *(*boxes)[i]);
                ++count;
            }
        }
        if (count == 0) throw Error(std::string("the ") + name + " detector found no training face");
        model.box_priors.push_back({name, sum / static_cast<float>(count)});
        logLine(std::string(name) + " box prior from " + std::to_string(count) + " detections");
    }
    const Shape68& prior = model.box_priors.front().shape;

    // Initial shapes: the prior on the real, then on perturbed, detector boxes;
    // other faces' shapes on the box; and the truth jittered as a tracker
    // would hand over the previous frame's shape.
    std::vector<landmarks::TrainingSample> samples;
    std::normal_distribution<float> normal(0.f, 1.f);
    std::uniform_int_distribution<int> anyImage(0, static_cast<int>(images.size()) - 1);
    for (int i = 0; i < static_cast<int>(images.size()); ++i) {
        const Box box = yunetBoxes[i] ? *yunetBoxes[i] : impliedBox(prior, images[i].truth);
        for (int k = 0; k < inits; ++k) {
            Shape68 shape;
            switch (k % 6) {
                case 0:
                    shape = onBox(prior, k == 0 ? box : jitter(box, 0.05f, 0.05f, rng));
                    break;
                case 1:
                case 2:
                    shape = onBox(prior, jitter(box, 0.05f, 0.05f, rng));
                    break;
                case 3:
                case 4: {
                    const int j = anyImage(rng);
                    const Box other = yunetBoxes[j] ? *yunetBoxes[j] : impliedBox(prior, images[j].truth);
                    shape = onBox(inBox(images[j].truth, other), jitter(box, 0.03f, 0.03f, rng));
                    break;
                }
                default: {
                    core::Similarity s;
                    s.angle = 4.f * float(M_PI) / 180.f * normal(rng);
                    s.scale = 1.f + 0.03f * normal(rng);
                    const Eigen::Vector2f c = images[i].truth.rowwise().mean();
                    s.translation = c - s.linear() * c + 0.03f * box.width() * Eigen::Vector2f(normal(rng), normal(rng));
                    shape = s.apply(images[i].truth);
                    for (int p = 0; p < core::kLandmarks; ++p) {
                        shape.col(p) += 0.01f * box.width() * Eigen::Vector2f(normal(rng), normal(rng));
                    }
                }
            }
            samples.push_back({i, shape});
        }
    }
    logLine(std::to_string(images.size()) + " images, " + std::to_string(samples.size()) + " samples, initial NME " +
            std::to_string(100 * landmarks::meanNme(images, samples)) + "%");

    const std::string partial = out + ".partial";
    if (args.has("--resume") && fs::exists(partial)) {
        const auto saved = landmarks::readLbfModel(partial);
        if (saved.trees_per_landmark != o.trees_per_landmark || saved.tree_depth != o.tree_depth) {
            throw Error("'" + partial + "' was trained with other settings; remove it or match them");
        }
        for (const auto& stage : saved.stages) {
            for (auto& s : samples) landmarks::applyStage(saved, stage, images[s.image].gray, s.shape);
            model.stages.push_back(stage);
        }
        logLine("resumed after stage " + std::to_string(model.stages.size()) + ", NME " +
                std::to_string(100 * landmarks::meanNme(images, samples)) + "%");
    }
    while (static_cast<int>(model.stages.size()) < o.stages) {
        landmarks::trainLbfStage(model, images, samples, o);
        landmarks::writeLbfModel(partial, model);
        logLine("stage " + std::to_string(model.stages.size()) + " done, training NME " +
                std::to_string(100 * landmarks::meanNme(images, samples)) + "%");
    }
    landmarks::writeLbfModel(out, model);
    fs::remove(partial);
    logLine("wrote " + out + " (" + std::to_string(fs::file_size(out) / 1e6) + " MB)");
    return 0;
}

}  // namespace
}  // namespace facetrack::tools

int main(int argc, char** argv) { return facetrack::tools::runTool("train_landmarks", facetrack::tools::run, argc, argv); }
