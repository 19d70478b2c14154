// eval_cnn: the CNN cascade's robustness figure. For every 300-W
// crop of a split (validation by default; never a training crop), starts
// perturbed from its dense teacher label (MediaPipe's mesh fitted with the
// face model: a teacher label, not ground truth) by yaw +-Y deg and scale
// +-D (uniform; the target: +-15 deg, +-10 %), then K rounds of the
// cascade (cnn/update_net.hpp). Reports per round the rotation error
// (the angle of R_est R_label^T), the depth error, the expression error and
// the share of starts within 3 deg of the label.
//
//   build/tools/eval_cnn [--cascade models/cnn_cascade.ftm] [--starts 5] [--split validation]
//                        [--yaw-deg 15] [--depth 0.1] [--labels build/dense_labels] [--profiled N]
//
// With --profiled N, also N tries per crop of a copy turned to large yaw by face
// profiling (profile/face_profiling.hpp, the large-pose evaluation set), the
// errors by 15 deg bin of the copy's |yaw|, from perturbed starts and from LBF + fit.
//
// When the cascade has a landmark net, also the landmarks against the 300-W
// annotation (carried to the profiled copies: profile::carriedLandmarks): the
// tracker's LBF alone and its whole pipeline (LBF, fit, cascade, landmark net;
// where the pipeline drops a face, LBF's landmarks), each from the tracker's own
// YuNet detection, as NME over the eye-corner distance (300-W) and over sqrt(w h)
// of the annotation's box (large poses).
//
// The rounds are the cascade's: each stage run as often as the file says.
//
//   build/tools/eval_cnn --tracker [--starts 5] [--split validation] [--yaw-deg 15] [--depth 0.1]
//                        [--reference build/dense_averaged/faces300w.csv]
//
// With --tracker, the same target for the pipeline that shipped instead (LBF, the
// landmark refiner, the fit; no cascade stages): trackerRobustness() below.
// --reference: the poses are compared with that table's labels (e.g. the labels
// averaged with their mirror images', label_mirror_consistency.py average)
// instead of --labels', which still make the perturbed starts.

#include "app/args.hpp"
#include "app/tool_main.hpp"
#include "cli/stats.hpp"
#include "common/faces300w.hpp"
#include "core/pts.hpp"
#include "core/shape2d.hpp"
#include "data/dense/dense_fit.hpp"
#include "data/dense/label_table.hpp"
#include "data/profile/face_profiling.hpp"
#include "expression/landmark_net.hpp"
#include "expression/update_net.hpp"
#include "facetrack/cnn_model.hpp"
#include "facetrack/detector.hpp"
#include "facetrack/face_model.hpp"
#include "facetrack/tracker.hpp"
#include "fit/face_fitter.hpp"
#include "landmarks/lbf.hpp"
#include "model/internals.hpp"
#include "nn/cnn_model_data.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <map>
#include <memory>
#include <optional>
#include <cstdio>
#include <random>

using namespace facetrack;

namespace {

/// The rotation angle of `r`, degrees.
double angleDeg(const Eigen::Matrix3d& r) { return Eigen::AngleAxisd(r).angle() * 180.0 / M_PI; }

double rotationErrorDeg(const fit::FaceParams& a, const fit::FaceParams& b) {
    return angleDeg(fit::rotationOf(a.omega()) * fit::rotationOf(b.omega()).transpose());
}

struct RoundErrors {
    std::vector<double> rotation_deg, depth_pct, expression;
};

/// Landmark errors of one method over a set of images.
struct LandmarkErrors {
    std::vector<double> eye_corner_nme, box_nme;
    int dropped = 0;  ///< faces the pipeline dropped (LBF's landmarks counted)
};

double meanOf(const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

void reportLandmarks(const char* name, const LandmarkErrors& e) {
    if (e.box_nme.empty()) return;
    std::printf("%-22s landmarks: %4zu faces, NME %5.2f %% of the eye-corner distance, %5.2f %% of sqrt(box)%s\n", name, e.box_nme.size(),
                100.0 * meanOf(e.eye_corner_nme), 100.0 * meanOf(e.box_nme),
                e.dropped ? (" (" + std::to_string(e.dropped) + " dropped: LBF's)").c_str() : "");
}

/// The rotations within 3 deg of their reference, percent.
double within3(const std::vector<double>& rotationDeg) {
    const auto n = std::count_if(rotationDeg.begin(), rotationDeg.end(), [](double x) { return x < 3.0; });
    return rotationDeg.empty() ? 0.0 : 100.0 * static_cast<double>(n) / static_cast<double>(rotationDeg.size());
}

double medianOf(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
}

void report(const char* name, const RoundErrors& e) {
    if (e.rotation_deg.empty()) {
        std::printf("%-8s no faces\n", name);
        return;
    }
    std::printf("%-8s rotation mean %5.2f median %5.2f deg, within 3 deg %5.1f %%; depth %5.2f %%; expression MAE %.4f\n", name,
                meanOf(e.rotation_deg), medianOf(e.rotation_deg), within3(e.rotation_deg), meanOf(e.depth_pct), meanOf(e.expression));
}

/// --tracker: the robustness target for the pipeline that shipped (LBF, the
/// landmark refiner, the fit; docs/cnn.md). A followed face whose previous
/// frame sat `yaw` and `scale` away: frame 1 is the crop profiled to its label
/// turned by d ~ U(-Y, Y) deg (profile::turnedBy; copies more than 15 % hidden
/// are drawn again) and scaled by 1 + U(-D, D) about its annotation's centre,
/// found by YuNet; frame 2 is the crop itself, followed with no full-frame search
/// (the tracker's own check near a face that no stage could place runs, as it does
/// live; where frame 2 still loses the face, also as a live tracker goes on: the
/// same frame searched again).
/// Frame 2's pose is compared with
///   - the label, after the mean rotation C between the tracker's poses and the
///     labels on the training crops (R_tracker ~ R_label C: the fit and the
///     teacher's mesh put the head's axes a few degrees apart, mostly in pitch);
///   - frame 2's pose when frame 1 is the crop itself (label-free: how often
///     the perturbed start leaves the answer within 3 deg of the unperturbed one);
///     as a control, when frame 1 is the crop profiled at its own pose (what the
///     re-rendering alone changes).
/// And what the 68 points can give at best: the tracker's fit (cold, as a still
/// image's) of the crop's *annotated* points, with the mean identity and with the
/// label's own, against the label after its own mean rotation C.
void trackerRobustness(const std::string& split, int starts, double yawDeg, double depth, const dense::LabelTable& table,
                       const std::optional<dense::LabelTable>& reference, const std::string& root) {
    const Models shipped = Models::loadDefault();
    const auto& model = shipped.face;
    std::vector<std::string> labelled;  // the model's expressions the labels have (not the gaze stage's eyeLook shapes)
    for (const auto& name : model->expressionNames())
        if (std::find(table.columns.begin(), table.columns.end(), name) != table.columns.end()) labelled.push_back(name);
    const dense::LabelColumns columns = dense::labelColumns(table, labelled);
    const std::vector<int> labelledIds = nn::expressionIndices(model->expressionNames(), labelled);
    TrackerConfig still;
    still.filter.enabled = false;  // frame 2's pose is its own, not smoothed towards frame 1's
    Tracker tracker(shipped, still);
    DetectorConfig yunet;
    yunet.kind = DetectorKind::YuNet;
    const auto detector = createFaceDetector(yunet);  // boxes as eval-landmarks takes them: the one on the annotated face
    FrameResult result;
    const auto view = [](const cv::Mat& m) { return ImageView{m.data, m.cols, m.rows, m.step, PixelFormat::Gray8}; };
    // The first face's head rotation, if it has a pose.
    const auto rotationOfFace = [](const FrameResult& frame, Eigen::Matrix3d& rotation) {
        if (frame.faces.empty() || !frame.faces[0].pose) return false;
        fit::FaceParams p;
        std::vector<int> none;
        expression::readParams(*frame.faces[0].pose, {}, none, p);
        rotation = fit::rotationOf(p.omega());
        return true;
    };
    // Frame 2's rotation: `first` (found by YuNet, as the face on `annotated`), then `second` followed;
    // with no `second`, frame 1's. Which frame lost the face, if one did.
    enum class Lost { None, FirstFrame, SecondFrame };
    const auto followed = [&](const cv::Mat& first, const core::Shape2& annotated, const cv::Mat& second, Eigen::Matrix3d& rotation) {
        const auto box = tools::matchingBox(detector->detect(view(first)), annotated);
        if (!box) return Lost::FirstFrame;
        tracker.reset();
        tracker.process(view(first), 0.0, {*box}, result);
        if (result.faces.empty()) return Lost::FirstFrame;
        if (second.data) tracker.process(view(second), 1.0 / 30.0, {}, result);
        return rotationOfFace(result, rotation) ? Lost::None : Lost::SecondFrame;
    };
    // The rotation each crop's pose is compared with: --reference's label, or the crop's own.
    std::map<std::string, Eigen::Matrix3d> referenceRotation;
    if (reference) {
        const dense::LabelColumns referenceColumns = dense::labelColumns(*reference, {});
        for (const auto& row : reference->rows)
            referenceRotation[row.key] = fit::rotationOf(dense::labelParams(referenceColumns, row).omega());
    }
    int unreferenced = 0;
    const auto referenced = [&](const dense::LabelTable::Row& row) {
        const bool found = !reference || referenceRotation.count(row.key) > 0;
        if (!found && row.split == split) ++unreferenced;
        return found;
    };
    struct Crop {
        cv::Mat grey;
        core::Shape2 annotated;
        fit::FaceParams label;
        Eigen::VectorXd identity;
        Eigen::Matrix3d reference;
    };
    // The fit of the annotated points, cold, with the mean identity (0) or the label's (1).
    const std::shared_ptr<const fit::FitBasis>& basis = fit::basisOf(model);
    const auto annotatedFit = [&](const Crop& c, int identity) {
        fit::FaceFitter fitter(basis, {});
        if (identity == 1) fitter.setIdentity(c.identity.head(std::min<Eigen::Index>(c.identity.size(), basis->identityCount())));
        fit::FaceParams p;
        fitter.fit(core::cameraFor(c.grey.cols, c.grey.rows, 60.0, 0.0), c.annotated.cast<double>(), p, false);
        return fit::rotationOf(p.omega());
    };
    const auto load = [&](const dense::LabelTable::Row& row) {
        Crop c;
        c.grey = cv::imread(root + "/" + row.key, cv::IMREAD_GRAYSCALE);
        if (c.grey.empty()) throw Error("cannot read " + root + "/" + row.key);
        c.annotated = core::readPts(root + "/" + row.key.substr(0, row.key.rfind('.')) + ".pts");
        if (c.annotated.cols() != 68) throw Error(row.key + ": its .pts does not have 68 points");
        c.label = dense::labelParams(columns, row);
        c.identity = dense::labelIdentity(columns, row);
        c.reference = reference ? referenceRotation.at(row.key) : fit::rotationOf(c.label.omega());
        return c;
    };

    // C: the mean of R_label^T R_tracker over the training crops found afresh, projected onto SO(3);
    // the same for the annotated points' fits.
    Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
    std::array<Eigen::Matrix3d, 2> annotatedSum = {Eigen::Matrix3d::Zero(), Eigen::Matrix3d::Zero()};
    int trainCrops = 0;
    for (const auto& row : table.rows) {
        if (row.split != "train" || !referenced(row)) continue;
        const Crop c = load(row);
        for (int identity = 0; identity < 2; ++identity) annotatedSum[identity] += c.reference.transpose() * annotatedFit(c, identity);
        Eigen::Matrix3d r;
        if (followed(c.grey, c.annotated, cv::Mat(), r) != Lost::None) continue;
        sum += c.reference.transpose() * r;
        if (++trainCrops % 100 == 0) std::fprintf(stderr, "\r%d training crops", trainCrops);
    }
    if (trainCrops == 0) throw Error("no training crops with a face: the offset between the tracker's and the labels' axes needs them");
    const auto nearestRotation = [](const Eigen::Matrix3d& m) {
        const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
        const double d = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
        return Eigen::Matrix3d(svd.matrixU() * Eigen::Vector3d(1, 1, d).asDiagonal() * svd.matrixV().transpose());
    };
    const Eigen::Matrix3d offset = nearestRotation(sum);
    const std::array<Eigen::Matrix3d, 2> annotatedOffset = {nearestRotation(annotatedSum[0]), nearestRotation(annotatedSum[1])};

    std::mt19937 rng(23);
    std::uniform_real_distribution<double> sym(-1.0, 1.0);
    std::vector<double> startDeg, toLabel, toUnperturbed, unperturbedToLabel, controlToUnperturbed, foundAgainToUnperturbed;
    std::array<std::vector<double>, 2> annotatedToLabel;
    std::array<std::vector<double>, 3> unperturbedEuler, labelEuler;  // pitch, yaw, roll (deg), the label's after C
    const auto eulerOf = [](const Eigen::Matrix3d& rotation) {
        const Eigen::AngleAxisd turn(rotation);
        return fit::eulerDegrees(turn.angle() * turn.axis());
    };
    int crops = 0, lostFirst = 0, lostSecond = 0, unfollowed = 0;
    for (const auto& row : table.rows) {
        if (row.split != split || !referenced(row)) continue;
        const Crop c = load(row);
        const core::Camera camera = core::cameraFor(c.grey.cols, c.grey.rows, 60.0, 0.0);
        const std::vector<float> identity(c.identity.data(), c.identity.data() + c.identity.size());
        const std::vector<float> expression = profile::nativeWeights(*model, labelledIds, c.label.expression);
        const Eigen::Matrix3d labelRotation = c.reference * offset;
        for (int identity = 0; identity < 2; ++identity) {
            const Eigen::Matrix3d labelled = c.reference * annotatedOffset[identity];
            annotatedToLabel[identity].push_back(angleDeg(annotatedFit(c, identity) * labelled.transpose()));
        }
        ++crops;
        Eigen::Matrix3d unperturbed;
        const bool haveUnperturbed = followed(c.grey, c.annotated, c.grey, unperturbed) == Lost::None;
        if (haveUnperturbed) {
            unperturbedToLabel.push_back(angleDeg(unperturbed * labelRotation.transpose()));
            const Eigen::Vector3d ours = eulerOf(unperturbed), theirs = eulerOf(labelRotation);
            for (int axis = 0; axis < 3; ++axis) unperturbedEuler[axis].push_back(ours[axis]), labelEuler[axis].push_back(theirs[axis]);
        } else {
            ++unfollowed;
        }
        // Control: frame 1 the crop profiled at its own pose, what profiling alone changes.
        const cv::Mat rendered = profile::profileFace(*model, c.grey, camera, identity, expression, c.label, c.label).image;
        Eigen::Matrix3d control;
        if (haveUnperturbed && followed(rendered, c.annotated, c.grey, control) == Lost::None)
            controlToUnperturbed.push_back(angleDeg(control * unperturbed.transpose()));
        const Eigen::Vector2f centre = 0.5f * (c.annotated.rowwise().minCoeff() + c.annotated.rowwise().maxCoeff());
        for (int s = 0; s < starts; ++s) {
            profile::ProfiledFace copy;
            fit::FaceParams turned;
            for (int draw = 0; draw < 20; ++draw) {
                turned = profile::turnedBy(c.label, yawDeg * sym(rng));
                copy = profile::profileFace(*model, c.grey, camera, identity, expression, c.label, turned);
                if (copy.hidden_share <= 0.15) break;
            }
            const double k = 1.0 + depth * sym(rng);
            const cv::Matx23d scaling(k, 0, centre.x() * (1 - k), 0, k, centre.y() * (1 - k));
            cv::Mat first;
            cv::warpAffine(copy.image, first, scaling, copy.image.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
            startDeg.push_back(rotationErrorDeg(turned, c.label));
            const core::Shape2 moved = (c.annotated * static_cast<float>(k)).colwise() + centre * static_cast<float>(1 - k);
            Eigen::Matrix3d r;
            if (const Lost lost = followed(first, moved, c.grey, r); lost != Lost::None) {
                ++(lost == Lost::FirstFrame ? lostFirst : lostSecond);
                // A live tracker that loses its face searches the same frame again (YuNet, a cold fit).
                if (lost == Lost::SecondFrame && haveUnperturbed && rotationOfFace(tracker.process(view(c.grey), 2.0 / 30.0, result), r))
                    foundAgainToUnperturbed.push_back(angleDeg(r * unperturbed.transpose()));
                continue;
            }
            toLabel.push_back(angleDeg(r * labelRotation.transpose()));
            if (haveUnperturbed) toUnperturbed.push_back(angleDeg(r * unperturbed.transpose()));
        }
        if (crops % 20 == 0) std::fprintf(stderr, "\r%d %s crops", crops, split.c_str());
    }
    std::fprintf(stderr, "\r");
    if (crops == 0) throw Error("no crops in split '" + split + "'");
    const Eigen::Vector3d offsetDeg = eulerOf(offset);
    std::printf(
        "the shipped tracker (dense teacher labels, not ground truth); C from %d training crops: %.2f deg "
        "(Euler pitch, yaw, roll %.2f, %.2f, %.2f)\n",
        trainCrops, angleDeg(offset), offsetDeg.x(), offsetDeg.y(), offsetDeg.z());
    if (reference)
        std::printf("the label compared with: --reference's (%d %s crops it does not have left out)\n", unreferenced, split.c_str());
    const auto line = [](const char* name, const std::vector<double>& deg) {
        if (deg.empty()) return (void)std::printf("  %-54s %5d\n", name, 0);
        std::printf("  %-54s %5zu, mean %5.2f median %5.2f deg, within 3 deg %5.1f %%\n", name, deg.size(), meanOf(deg), medianOf(deg),
                    within3(deg));
    };
    std::printf(
        "%d %s crops x %d starts: frame 1 the crop turned by yaw +-%.0f deg (uniform) and scaled by +-%.0f %%, frame 2 the crop, "
        "followed with no full-frame search (starts lost: %d on frame 1, %d on frame 2; %d crops not followed unperturbed)\n",
        crops, split.c_str(), starts, yawDeg, 100.0 * depth, lostFirst, lostSecond, unfollowed);
    line("start (frame 1's pose) to the label", startDeg);
    line("frame 2 to the label (after C)", toLabel);
    line("unperturbed (frame 1 the crop) to the label", unperturbedToLabel);
    // Per Euler angle, the least-squares line ours = a label + b and the spread about it.
    std::printf("  %-54s", "unperturbed against the label, per angle: ours =");
    const char* const angleNames[3] = {"pitch", "yaw", "roll"};
    for (int axis = 0; axis < 3 && unperturbedEuler[axis].size() > 1; ++axis) {
        const cli::Line fitted = cli::leastSquaresLine(labelEuler[axis], unperturbedEuler[axis]);
        std::printf(" %s %.3f x label, spread %.2f deg%s", angleNames[axis], fitted.slope, fitted.spread, axis < 2 ? ";" : "");
    }
    std::putchar('\n');
    line("frame 2 to the unperturbed (label-free)", toUnperturbed);
    const int comparable = starts * (crops - unfollowed);  // the label-free figure's starts, lost ones included
    const auto hits = [](const std::vector<double>& deg) { return within3(deg) * static_cast<double>(deg.size()); };
    std::printf("  %-54s %5d, within 3 deg %5.1f %%\n", "the same, the starts lost counted as misses", comparable,
                hits(toUnperturbed) / std::max(comparable, 1));
    line("frame 2 lost, searched again (YuNet), to the unperturbed", foundAgainToUnperturbed);
    std::printf("  %-54s %5d, within 3 deg %5.1f %%\n", "the same, a live tracker's search counted", comparable,
                (hits(toUnperturbed) + hits(foundAgainToUnperturbed)) / std::max(comparable, 1));
    line("control: frame 1 profiled unturned, to the unperturbed", controlToUnperturbed);
    std::printf("what the 68 points give at best: the fit of the annotated points, cold, to the label (after their own C)\n");
    line("with the mean identity (a still image's)", annotatedToLabel[0]);
    line("with the label's identity", annotatedToLabel[1]);
}

int run(int argc, char** argv) {
    const tools::Args args(
        std::vector<std::string>(argv + 1, argv + argc),
        {"--cascade", "--starts", "--split", "--yaw-deg", "--depth", "--labels", "--faces300w", "--profiled", "--reference"},
        {"--help", "--tracker"});
    if (args.has("--help")) {
        std::puts(
            "usage: eval_cnn [--cascade models/cnn_cascade.ftm] [--starts 5] [--split validation]\n"
            "       [--yaw-deg 15] [--depth 0.1] [--labels build/dense_labels] [--faces300w DIR] [--profiled N]\n"
            "       eval_cnn --tracker [--starts 5] [--split validation] [--yaw-deg 15] [--depth 0.1] [--labels DIR] [--faces300w DIR]\n"
            "                [--reference LABELS.csv]");
        return 0;
    }
    const std::string split = args.get("--split", "validation");
    if (split == "train") throw Error("eval_cnn measures held-out crops: --split validation or test");
    const int starts = args.integer("--starts", 5);
    const double yawDeg = args.number("--yaw-deg", 15.0), depth = args.number("--depth", 0.10);
    if (starts < 1) throw Error("--starts must be at least 1");
    if (args.has("--tracker")) {
        std::optional<dense::LabelTable> reference;
        if (args.has("--reference")) reference = dense::readLabelTable(args.get("--reference"));
        trackerRobustness(split, starts, yawDeg, depth,
                          dense::readLabelTable(args.get("--labels", "build/dense_labels") + "/faces300w.csv"), reference,
                          tools::faces300wRoot(args.get("--faces300w", "")));
        return 0;
    }

    const auto model = FaceModel::loadDefault();  // the shipped tracker's: with the landmark convention
    const auto cascade = CnnModel::load(args.get("--cascade", CnnModel::defaultPath()));
    const nn::CnnModelData& data = model::dataOf(*cascade);
    const std::vector<int> expressionIds = nn::expressionIndices(model->expressionNames(), data.expressions);
    const expression::WarpLayout layout = expression::makeWarpLayout(model::dataOf(*model), expressionIds, data.patch_size);
    std::vector<nn::PatchNet> nets;
    std::vector<std::size_t> roundNet;  // per round, its stage
    for (std::size_t i = 0; i < data.stages.size(); ++i) {
        nets.emplace_back(data.stages[i].onnx, data.patch_size, 6 + static_cast<int>(data.expressions.size()),
                          "stage " + std::to_string(i + 1));
        roundNet.insert(roundNet.end(), static_cast<std::size_t>(data.stages[i].rounds), i);
    }
    const int iterations = static_cast<int>(roundNet.size());

    const auto table = dense::readLabelTable(args.get("--labels", "build/dense_labels") + "/faces300w.csv");
    const dense::LabelColumns columns = dense::labelColumns(table, data.expressions);
    const std::string root = tools::faces300wRoot(args.get("--faces300w", ""));
    std::mt19937 rng(23);
    std::uniform_real_distribution<double> sym(-1.0, 1.0);
    std::vector<RoundErrors> rounds(static_cast<std::size_t>(iterations + 1)), fromFit(static_cast<std::size_t>(iterations + 1));
    const int profiledTries = args.integer("--profiled", 0);
    constexpr int kBins = 5;  // |yaw| 15-30, ..., 75-90 deg
    std::vector<std::vector<RoundErrors>> binned(kBins, std::vector<RoundErrors>(static_cast<std::size_t>(iterations + 1)));
    std::vector<std::vector<RoundErrors>> binnedFit(kBins, std::vector<RoundErrors>(static_cast<std::size_t>(iterations + 1)));
    std::vector<int> binFaces(kBins, 0), binUnfitted(kBins, 0);
    // The other start: what the tracker's LBF + fit say of the still crop (mean identity, as a
    // face's first frames have).
    TrackerConfig still;
    still.filter.enabled = false;
    const auto lbfModel = LandmarkModel::loadDefault();
    Tracker lbf(Models{model, lbfModel, nullptr, nullptr, nullptr}, still);
    FrameResult result, fullResult;
    // The whole pipeline, when the cascade moves the landmarks too.
    std::unique_ptr<Tracker> full;
    if (cascade->hasLandmarkNet()) full = std::make_unique<Tracker>(Models{model, lbfModel, nullptr, cascade, nullptr}, still);
    const fit::FitBasis landmarkBasis = expression::landmarkBasis(*model, expressionIds);  // to carry the annotation to profiled copies
    DetectorConfig yunet;
    yunet.kind = DetectorKind::YuNet;
    const auto detector = createFaceDetector(yunet);
    LandmarkErrors cropLbf, cropFull;
    // The real crops (no profiling) by the label's |yaw|: 0-15, 15-30, 30-45, over 45 deg.
    std::vector<LandmarkErrors> cropBinLbf(4), cropBinFull(4);
    std::vector<LandmarkErrors> binLbf(kBins), binFull(kBins);
    expression::RefineWork work;
    const auto record = [&](std::vector<RoundErrors>& errors, int round, const fit::FaceParams& params, const fit::FaceParams& label) {
        RoundErrors& e = errors[static_cast<std::size_t>(round)];
        e.rotation_deg.push_back(rotationErrorDeg(params, label));
        e.depth_pct.push_back(100.0 * std::abs(params.pose[5] - label.pose[5]) / label.pose[5]);
        e.expression.push_back((params.expression - label.expression).cwiseAbs().mean());
    };
    const auto cascadeFrom = [&](fit::FaceParams params, const fit::FaceParams& label, const cv::Mat& grey, const core::Camera& camera,
                                 std::vector<RoundErrors>& errors) {
        for (int i = 0; i <= iterations; ++i) {
            if (i > 0) expression::refine(layout, nets[roundNet[static_cast<std::size_t>(i - 1)]], grey, camera, params, 1, work);
            record(errors, i, params, label);
        }
    };
    int crops = 0, unfitted = 0;
    for (const auto& row : table.rows) {
        if (row.split != split) continue;
        const cv::Mat grey = cv::imread(root + "/" + row.key, cv::IMREAD_GRAYSCALE);
        if (grey.empty()) throw Error("cannot read " + root + "/" + row.key);
        const core::Camera camera = core::cameraFor(grey.cols, grey.rows, 60.0, 0.0);
        const fit::FaceParams label = dense::labelParams(columns, row);
        const Eigen::VectorXd labelIdentity = dense::labelIdentity(columns, row);
        // One image: `starts` perturbed starts, and the tracker's LBF + fit, each through the cascade.
        const auto landmarkErrors = [&](const cv::Mat& image, const Box& box, const fit::Landmarks2d& points, LandmarkErrors& ofLbf,
                                        LandmarkErrors& ofFull) {
            const auto shape = [](const Landmarks68& l) { return core::Shape2(core::fromLandmarks68(l)); };
            const core::Shape2 truthShape = points.cast<float>();
            const core::Shape2 fromLbf = shape(*result.faces[0].landmarks);
            full->reset();
            full->process(ImageView{image.data, image.cols, image.rows, image.step, PixelFormat::Gray8}, 0.0, {box}, fullResult);
            const bool kept = !fullResult.faces.empty() && fullResult.faces[0].landmarks;
            const core::Shape2 fromFull = kept ? shape(*fullResult.faces[0].landmarks) : fromLbf;
            ofFull.dropped += !kept;
            for (auto [errors, s] : {std::pair{&ofLbf, &fromLbf}, std::pair{&ofFull, &fromFull}}) {
                errors->eye_corner_nme.push_back(core::nme68(*s, truthShape));
                errors->box_nme.push_back(core::nmeBox(*s, truthShape));
            }
        };
        const auto evaluate = [&](const cv::Mat& image, const fit::FaceParams& truth, const fit::Landmarks2d& points,
                                  std::vector<RoundErrors>& perturbed, std::vector<RoundErrors>& fitted, LandmarkErrors& ofLbf,
                                  LandmarkErrors& ofFull) {
            work.identity_shape = fit::shapeWithIdentity(layout.anchors, labelIdentity);
            for (int s = 0; s < starts; ++s) {
                fit::FaceParams params = truth;  // turned about the face centre and scaled
                Eigen::VectorXd move = Eigen::VectorXd::Zero(6);
                move[1] = yawDeg * M_PI / 180.0 * sym(rng);
                const Eigen::Vector3d centre = fit::rotationOf(truth.omega()) * layout.centre + truth.translation();
                move.segment<3>(3) = depth * sym(rng) * centre / centre.z();
                expression::applyUpdate(layout, move, params);
                cascadeFrom(params, truth, image, camera, perturbed);
            }
            // The tracker starts from YuNet's box of this face (as eval-landmarks does; a crop can show others).
            const ImageView view{image.data, image.cols, image.rows, image.step, PixelFormat::Gray8};
            const auto box = tools::matchingBox(detector->detect(view), points.cast<float>());
            if (!box) return false;
            lbf.reset();
            lbf.process(view, 0.0, {*box}, result);
            if (result.faces.empty() || !result.faces[0].pose || !result.faces[0].expression) return false;
            if (full) landmarkErrors(image, *box, points, ofLbf, ofFull);
            fit::FaceParams start;
            expression::readParams(*result.faces[0].pose, result.faces[0].expression->native, expressionIds, start);
            work.identity_shape = fit::shapeWithIdentity(layout.anchors, Eigen::VectorXd());
            cascadeFrom(start, truth, image, camera, fitted);
            return true;
        };
        const core::Shape2 annotated = core::readPts(root + "/" + row.key.substr(0, row.key.rfind('.')) + ".pts");
        if (annotated.cols() != 68) throw Error(row.key + ": its .pts does not have 68 points");
        const fit::Landmarks2d points = annotated.cast<double>();
        const auto cropBin = static_cast<std::size_t>(std::min(3, static_cast<int>(std::abs(fit::eulerDegrees(label.omega()).y()) / 15.0)));
        const std::size_t before = cropLbf.box_nme.size();
        if (!evaluate(grey, label, points, rounds, fromFit, cropLbf, cropFull)) ++unfitted;
        if (cropLbf.box_nme.size() > before) {  // this crop's landmark errors, into its yaw bin too
            for (auto [all, bin] : {std::pair{&cropLbf, &cropBinLbf[cropBin]}, std::pair{&cropFull, &cropBinFull[cropBin]}}) {
                bin->eye_corner_nme.push_back(all->eye_corner_nme.back());
                bin->box_nme.push_back(all->box_nme.back());
            }
        }
        if (profiledTries > 0) {
            const std::vector<float> identity(labelIdentity.data(), labelIdentity.data() + labelIdentity.size());
            for (const auto& copy :
                 profile::profiledCopies(*model, grey, camera, identity, profile::nativeWeights(*model, expressionIds, label.expression),
                                         label, profiledTries, rng)) {
                const int bin = std::clamp(static_cast<int>(std::abs(fit::eulerDegrees(copy.label.omega()).y()) / 15.0) - 1, 0, kBins - 1);
                ++binFaces[static_cast<std::size_t>(bin)];
                const fit::Landmarks2d carried = profile::carriedLandmarks(layout, landmarkBasis, labelIdentity, camera, label, points,
                                                                           copy.label);
                const auto b = static_cast<std::size_t>(bin);
                if (!evaluate(copy.image, copy.label, carried, binned[b], binnedFit[b], binLbf[b], binFull[b])) ++binUnfitted[b];
            }
        }
        if (++crops % 20 == 0) std::fprintf(stderr, "\r%d crops", crops);
    }
    if (crops == 0) throw Error("no crops in split '" + split + "'");
    std::fprintf(stderr, "\r");
    std::printf("%d %s crops x %d starts (yaw +-%.0f deg, scale +-%.0f %%), against the dense teacher labels:\n", crops, split.c_str(),
                starts, yawDeg, 100.0 * depth);
    for (int i = 0; i <= iterations; ++i)
        report(i == 0 ? "start" : ("round " + std::to_string(i)).c_str(), rounds[static_cast<std::size_t>(i)]);
    std::printf("from the tracker's LBF + fit (%d crops; %d without a YuNet box or a fitted face):\n", crops - unfitted, unfitted);
    for (int i = 0; i <= iterations; ++i)
        report(i == 0 ? "fit" : ("round " + std::to_string(i)).c_str(), fromFit[static_cast<std::size_t>(i)]);
    reportLandmarks("LBF", cropLbf);
    reportLandmarks("LBF + fit + CNN", cropFull);
    for (std::size_t b = 0; b < 4; ++b) {
        if (cropBinLbf[b].box_nme.empty()) continue;
        std::printf("crops with label |yaw| %s deg:\n",
                    b == 3 ? "over 45" : (std::to_string(15 * b) + "-" + std::to_string(15 * b + 15)).c_str());
        reportLandmarks("  LBF", cropBinLbf[b]);
        reportLandmarks("  LBF + fit + CNN", cropBinFull[b]);
    }
    for (int bin = 0; bin < kBins; ++bin) {
        if (binFaces[static_cast<std::size_t>(bin)] == 0) continue;
        std::printf("profiled, |yaw| %d-%d deg: %d faces (%d without a YuNet box or a fitted face)\n", 15 * (bin + 1), 15 * (bin + 2),
                    binFaces[static_cast<std::size_t>(bin)], binUnfitted[static_cast<std::size_t>(bin)]);
        const auto& b = binned[static_cast<std::size_t>(bin)];
        const auto& f = binnedFit[static_cast<std::size_t>(bin)];
        report("  start", b.front());
        report("  cascade", b.back());
        if (!f.front().rotation_deg.empty()) report("  fit", f.front()), report("  fit+cnn", f.back());
        reportLandmarks("  LBF", binLbf[static_cast<std::size_t>(bin)]);
        reportLandmarks("  LBF + fit + CNN", binFull[static_cast<std::size_t>(bin)]);
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) { return tools::runTool("eval_cnn", run, argc, argv); }
