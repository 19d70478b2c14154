// train_eyes: trains the gaze stage's eye model (facetrack/eye_model.hpp) on
// MediaPipe teacher labels (../shared/data/teacher: another model's
// predictions, not ground truth). Eye patches are cut with facetrack's own
// landmarks, as the stage will cut them. Held out: the 300-W validation and
// test splits and the clips named by --holdout (docs/gaze.md).
//
//   build/tools/train_eyes --out models/eye_model.ftm

#include "app/args.hpp"
#include "app/image_view.hpp"
#include "cli/stats.hpp"
#include "common/clip_splits.hpp"
#include "common/faces300w.hpp"
#include "common/npy_writer.hpp"
#include "common/synthetic_face.hpp"
#include "common/teacher.hpp"
#include "gaze/eye_model_data.hpp"
#include "gaze/forest_training.hpp"
#include "gaze/iris_net.hpp"

#include "core/binary_io.hpp"
#include "core/box.hpp"
#include "core/environment.hpp"
#include "core/pts.hpp"
#include "facetrack/facetrack.hpp"

#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <mutex>
#include <numeric>
#include <random>
#include <regex>
#include <sstream>

using namespace facetrack;
using namespace facetrack::gaze;

namespace {

const char* kUsage = R"(usage: train_eyes [--out models/eye_model.ftm] [--holdout CLIP,CLIP]
                  [--pixel-trees N] [--pixel-depth D] [--aperture-trees N] [--aperture-depth D] [--seed S]
                  [--synthetic RENDERS] [--synthetic-pixels] [--samples-out DIR]
                  [--corner-trees N] [--corner-depth D] [--corner-stages K]
                  [--corner-synthetic RENDERS] [--iris-net NET.onnx [--net-map-radius R]] [--from MODEL.ftm [--corners]]
Trains the eye model on the teacher labels in ../shared/data/teacher. Held out from training:
300-W validation and test, and the clips of --holdout (default: the held-out people of
data/clip_splits.csv). The aperture forest also learns from RENDERS synthetic renders of
the face model (default 2,500; exact classes and apertures; eval-gaze renders others), and the pixel
forest too with --synthetic-pixels. Reports pixel accuracy and aperture error on held-out eyes.
--samples-out DIR writes the eye patches instead, for the iris CNN (train_iris_net.py):
DIR/{train,validation,heldout}_{patches,classes,info}.npy, then stops.
--iris-net puts that CNN in the model, in place of the pixel forest: its maps averaged over boxes of
(2R + 1)^2 cells (default R = 1), their lid gap mapped onto the forest's scale (least squares over the
training clips' eyes). The corner cascade (the eye
corners refined from the patch, which place the eyeballs; default 4 stages) learns the 300-W
annotators' corners of the train split and the exact corners of RENDERS other renders (default
12,000), from patches cut near them; reported on 300-W validation and every tenth render, their
patches cut where facetrack's landmarks put the corners. --from MODEL.ftm adds to an existing
model (its forests kept) instead of training one: the iris net (--iris-net) and/or a new corner
cascade (--corners).)";

struct EyeSample {
    cv::Mat patch;
    tools::PatchLabels labels;
    bool iris_usable = true;  ///< the teacher's iris is trusted (300-W: inside the annotated eye)
    cv::Mat classes;          ///< synthetic eyes: the exact class of every patch pixel (CV_8U)
};

/// A synthetic eye's aperture, measured as the teacher's is: the visible eye's
/// height at 35, 50 and 65 % of the way between the corners, over the eye width.
float apertureOfClasses(const cv::Mat& classes) {
    float gap = 0.f;
    for (const float s : {0.35f, 0.5f, 0.65f}) {
        const int x = static_cast<int>(std::lround(kOuterX + s * kEyeWidth));
        int open = 0;
        for (int y = 0; y < classes.rows; ++y) open += classes.at<std::uint8_t>(y, x) > 0;
        gap += static_cast<float>(open) / 3.f;
    }
    return gap / kEyeWidth;
}

struct Dataset {
    std::vector<EyeSample> eyes;
    void add(const cv::Mat& gray, const Landmarks68& landmarks, const tools::TeacherRecord& teacher, bool trusted, std::mt19937* jitter) {
        for (const Eye eye : {Eye::Left, Eye::Right}) {
            Point2 outer = landmarks[static_cast<std::size_t>(outerCorner(eye))];
            Point2 inner = landmarks[static_cast<std::size_t>(innerCorner(eye))];
            if (jitter) {  // landmark noise, as the tracker's own corners have
                const float w = std::hypot(inner.x - outer.x, inner.y - outer.y);
                std::normal_distribution<float> n(0.f, 0.03f * w);
                outer.x += n(*jitter), outer.y += n(*jitter), inner.x += n(*jitter), inner.y += n(*jitter);
            }
            EyePatch patch;
            if (!cutEyePatch(gray, outer, inner, eye == Eye::Left, patch)) continue;
            EyeSample s;
            s.labels = tools::patchLabels(teacher.eye(eye), patch);
            const Point2 c = s.labels.iris_centre;
            // Our landmarks and the teacher's must be on the same eye.
            if (!(c.x > 0 && c.x < kPatchWidth && c.y > 0 && c.y < kPatchHeight)) continue;
            s.patch = patch.pixels.clone();
            s.iris_usable = trusted && teacher.eye(eye).in_pts_eye;
            eyes.push_back(std::move(s));
        }
    }
};

/// The tracker's unfiltered landmarks of the face nearest the teacher's irises.
std::optional<Landmarks68> landmarksFor(const FrameResult& result, const tools::TeacherRecord& teacher) {
    std::optional<Landmarks68> best;
    float bestDistance = 1e9f;
    for (const FaceResult& f : result.faces) {
        if (!f.landmarks) continue;
        const Landmarks68& l = *f.landmarks;
        const float d = std::hypot(l[45].x - teacher.left.iris_centre.x, l[45].y - teacher.left.iris_centre.y) +
                        std::hypot(l[36].x - teacher.right.iris_centre.x, l[36].y - teacher.right.iris_centre.y);
        if (d < bestDistance) bestDistance = d, best = l;
    }
    return best;
}

/// The landmark stages only: the eye model being trained is not needed (nor the old one loaded).
Models landmarkModels() { return Models{FaceModel::loadDefault(), LandmarkModel::loadDefault(), nullptr, nullptr, nullptr}; }

TrackerConfig unfiltered() {
    TrackerConfig c;
    c.filter.enabled = false;
    return c;
}

void addFaces300W(Dataset& data, const std::string& shared, tools::Split split, std::mt19937* jitter) {
    const std::string root = tools::faces300wRoot("");
    const auto teacher = tools::readTeacher(shared + "/data/teacher/faces300w_iris.jsonl");
    Tracker tracker(landmarkModels(), unfiltered());
    FrameResult result;
    for (const auto& image : tools::list300W(root, split)) {
        const std::string key = std::filesystem::relative(image.image, root).string();
        const auto t = teacher.find(key);
        if (t == teacher.end()) continue;
        const cv::Mat bgr = cv::imread(image.image, cv::IMREAD_COLOR);
        if (bgr.empty()) continue;
        tracker.reset();
        tracker.process(tools::viewOf(bgr), 0.0, result);
        const auto l = landmarksFor(result, t->second);
        if (!l) continue;
        cv::Mat gray;
        cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
        data.add(gray, *l, t->second, true, nullptr);
        if (jitter) data.add(gray, *l, t->second, true, jitter);
    }
}

void addClip(Dataset& data, const std::string& shared, const std::map<std::string, tools::TeacherRecord>& teacher, const std::string& clip,
             std::mt19937* jitter) {
    cv::VideoCapture video(shared + "/data/clips/" + clip);
    if (!video.isOpened()) throw Error("cannot open clip " + clip);
    Tracker tracker(landmarkModels(), unfiltered());
    FrameResult result;
    cv::Mat bgr, gray;
    for (int frame = 0; video.read(bgr); ++frame) {
        tracker.process(tools::viewOf(bgr), frame / 30.0, result);
        const auto t = teacher.find(tools::teacherKey(clip, frame));
        if (t == teacher.end()) continue;
        const auto l = landmarksFor(result, t->second);
        if (!l) continue;
        cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
        data.add(gray, *l, t->second, true, nullptr);
        if (jitter && frame % 2 == 0) data.add(gray, *l, t->second, true, jitter);
    }
}

/// A random render for training (its own generator, not eval-gaze's): head
/// pose, size, gaze, blinks, skin, iris, lashes, light, noise and blur.
tools::SyntheticFace randomTrainingFace(std::mt19937& rng, const std::vector<std::string>& names, unsigned seed) {
    std::uniform_real_distribution<float> unit(0.f, 1.f);
    const auto in = [&](float lo, float hi) { return lo + (hi - lo) * unit(rng); };
    const auto index = [&](const std::string& n) {
        return static_cast<std::size_t>(std::find(names.begin(), names.end(), n) - names.begin());
    };
    tools::SyntheticFace f;
    const float iod = in(35, 140);
    f.translation_mm = {in(-40, 40), in(-30, 30), f.fx * 62.3f / iod};
    const Eigen::Quaternionf q = Eigen::Quaternionf(0.f, 1.f, 0.f, 0.f) *
                                 Eigen::AngleAxisf(in(-35, 35) * 0.01745f, Eigen::Vector3f::UnitY()) *
                                 Eigen::AngleAxisf(in(-15, 15) * 0.01745f, Eigen::Vector3f::UnitX()) *
                                 Eigen::AngleAxisf(in(-10, 10) * 0.01745f, Eigen::Vector3f::UnitZ());
    f.rotation = {q.w(), q.x(), q.y(), q.z()};
    const float yaw = in(-32, 32), pitch = in(-25, 22), vergence = in(0, 6);
    f.gaze_deg = {{{yaw - vergence / 2, pitch}, {yaw + vergence / 2, pitch}}};
    f.expression.assign(names.size(), 0.f);
    for (const char* side : {"_L", "_R"}) {
        f.expression[index(std::string("eyeBlink") + side)] = unit(rng) < 0.3f ? in(0.f, 1.f) : 0.f;
        f.expression[index(std::string(pitch < 0 ? "eyeLookDown" : "eyeLookUp") + side)] = std::fabs(pitch) / 30.f * in(0.5f, 1.f);
    }
    f.skin = in(0.45f, 1.15f);
    f.iris = in(0.4f, 1.8f);
    f.lash = in(0.3f, 1.6f);
    f.light = {in(-0.8f, 0.8f), in(-0.8f, 0.4f), -1.f};
    f.noise_sigma = in(1.f, 5.f);
    f.blur_sigma = in(0.f, 1.2f);
    f.seed = seed;
    return f;
}

/// Renders `renders` faces of randomTrainingFace (seeded by `seed`), tracks
/// each as a new face from its box, and calls visit(renderer, face, image,
/// exact classes, landmarks) for each the tracker found.
template <class Visit>
void trackTrainingRenders(int renders, unsigned seed, Visit visit) {
    const Models models = landmarkModels();
    tools::SyntheticRenderer renderer(models.face);
    TrackerConfig config = unfiltered();
    config.camera.focal_length_px = tools::SyntheticFace{}.fx;
    Tracker tracker(models, config);
    std::mt19937 rng(seed);
    FrameResult result;
    for (int i = 0; i < renders; ++i) {
        const tools::SyntheticFace f = randomTrainingFace(rng, models.face->expressionNames(), seed * 100003u + static_cast<unsigned>(i));
        tools::ClassMap classes;
        const cv::Mat image = renderer.render(f, &classes);
        tracker.reset();
        tracker.process(tools::viewOf(image), 0.0, {renderer.faceBox(f)}, result);
        if (!result.faces.empty() && result.faces[0].landmarks) visit(renderer, f, image, classes, *result.faces[0].landmarks);
    }
}

/// Renders of the face model (tools/common/synthetic_face.hpp) with exact pixel
/// classes: eyes at every gaze, head pose and size, which the teacher's data has
/// few of. Their parameters come from their own generator (`seed`), not the
/// one eval-gaze's renders use.
void addSynthetic(Dataset& data, int renders, unsigned seed, std::mt19937& jitter) {
    trackTrainingRenders(renders, seed,
                         [&](const tools::SyntheticRenderer&, const tools::SyntheticFace&, const cv::Mat& image,
                             const tools::ClassMap& classes, const Landmarks68& landmarks) {
                             cv::Mat gray;
                             cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
                             for (int variant = 0; variant < 2; ++variant) {
                                 for (const Eye eye : {Eye::Left, Eye::Right}) {
                                     Point2 outer = landmarks[static_cast<std::size_t>(outerCorner(eye))];
                                     Point2 inner = landmarks[static_cast<std::size_t>(innerCorner(eye))];
                                     if (variant == 1) {
                                         const float w = std::hypot(inner.x - outer.x, inner.y - outer.y);
                                         std::normal_distribution<float> n(0.f, 0.03f * w);
                                         outer.x += n(jitter), outer.y += n(jitter), inner.x += n(jitter), inner.y += n(jitter);
                                     }
                                     EyePatch patch;
                                     if (!cutEyePatch(gray, outer, inner, eye == Eye::Left, patch)) continue;
                                     EyeSample s;
                                     s.patch = patch.pixels.clone();
                                     s.classes = cv::Mat(kPatchHeight, kPatchWidth, CV_8U);
                                     for (int y = 0; y < kPatchHeight; ++y) {
                                         for (int x = 0; x < kPatchWidth; ++x) {
                                             const Point2 p = toImage(patch, {static_cast<float>(x), static_cast<float>(y)});
                                             const int px = std::clamp(static_cast<int>(std::lround(p.x)), 0, classes.cols - 1);
                                             const int py = std::clamp(static_cast<int>(std::lround(p.y)), 0, classes.rows - 1);
                                             s.classes.at<std::uint8_t>(y, x) = classes.at<std::uint8_t>(py, px);
                                         }
                                     }
                                     s.labels.aperture = apertureOfClasses(s.classes);
                                     data.eyes.push_back(std::move(s));
                                 }
                             }
                         });
}

int pixelClassOf(const EyeSample& e, int x, int y) {
    return e.classes.empty() ? e.labels.pixelClass(static_cast<float>(x), static_cast<float>(y)) : e.classes.at<std::uint8_t>(y, x);
}

PatchFeature drawPixelTest(std::mt19937& rng) {
    std::uniform_int_distribution<int> offset(-kPixelTestReach, kPixelTestReach), kind(0, 19);
    PatchFeature f;
    const int k = kind(rng);
    f.kind = k < 14 ? PatchFeature::Difference : k < 18 ? PatchFeature::Intensity : k < 19 ? PatchFeature::Row : PatchFeature::Column;
    f.ax = static_cast<std::int8_t>(offset(rng));
    f.ay = static_cast<std::int8_t>(offset(rng));
    f.bx = static_cast<std::int8_t>(offset(rng));
    f.by = static_cast<std::int8_t>(offset(rng));
    return f;
}

PatchFeature drawPatchTest(std::mt19937& rng) {
    std::uniform_int_distribution<int> x(kClassifiedRegion.x0, kClassifiedRegion.x1 - 1), y(kClassifiedRegion.y0, kClassifiedRegion.y1 - 1),
        kind(0, 4);
    PatchFeature f;
    f.kind = kind(rng) < 4 ? PatchFeature::Difference : PatchFeature::Intensity;
    f.ax = static_cast<std::int8_t>(x(rng));
    f.ay = static_cast<std::int8_t>(y(rng));
    f.bx = static_cast<std::int8_t>(x(rng));
    f.by = static_cast<std::int8_t>(y(rng));
    return f;
}

struct PixelSet {
    std::vector<cv::Mat> patches;
    std::vector<PatchSample> samples;
    std::vector<float> targets;
};

PixelSet pixelSamples(const Dataset& data, int perPatch, unsigned seed, bool withSynthetic) {
    PixelSet set;
    std::mt19937 rng(seed);
    const PatchRegion r = kClassifiedRegion;
    std::uniform_int_distribution<int> x(r.x0, r.x1 - 1), y(r.y0, r.y1 - 1);
    for (const EyeSample& e : data.eyes) {
        if (!e.iris_usable || (!e.classes.empty() && !withSynthetic)) continue;
        const int p = static_cast<int>(set.patches.size());
        set.patches.push_back(e.patch);
        for (int i = 0; i < perPatch; ++i) {
            PatchSample s{p, x(rng), y(rng)};
            if (i % 4 == 3 && e.classes.empty()) {  // a quarter near the iris, where the boundary is
                std::normal_distribution<float> n(0.f, e.labels.iris_radius + 1.f);
                s.x = std::clamp(static_cast<int>(std::lround(e.labels.iris_centre.x + n(rng))), r.x0, r.x1 - 1);
                s.y = std::clamp(static_cast<int>(std::lround(e.labels.iris_centre.y + n(rng))), r.y0, r.y1 - 1);
            }
            set.samples.push_back(s);
            const int c = pixelClassOf(e, s.x, s.y);
            for (int k = 0; k < kPixelClasses; ++k) set.targets.push_back(k == c ? 1.f : 0.f);
        }
    }
    return set;
}

void reportPixels(const PatchForest& forest, const Dataset& data, const char* name) {
    long correct = 0, total = 0, irisBoth = 0, irisEither = 0;
    const PatchRegion r = kClassifiedRegion;
    float p[kPixelClasses];
    for (const EyeSample& e : data.eyes) {
        if (!e.iris_usable) continue;
        for (int y = r.y0; y < r.y1; ++y) {
            for (int x = r.x0; x < r.x1; ++x) {
                forest.evaluate(e.patch, x, y, p);
                const int predicted = static_cast<int>(std::max_element(p, p + kPixelClasses) - p);
                const int truth = pixelClassOf(e, x, y);
                correct += predicted == truth;
                ++total;
                irisBoth += predicted == kIris && truth == kIris;
                irisEither += predicted == kIris || truth == kIris;
            }
        }
    }
    std::printf("  %s: pixel accuracy %.3f, iris IoU %.3f over %ld pixels\n", name, total ? double(correct) / total : 0.0,
                irisEither ? double(irisBoth) / irisEither : 0.0, total);
}

void reportAperture(const PatchForest& forest, const Dataset& data, const char* name) {
    double absError = 0, sumT = 0, sumP = 0, sumTT = 0, sumPP = 0, sumTP = 0;
    const double n = static_cast<double>(data.eyes.size());
    for (const EyeSample& e : data.eyes) {
        float a;
        forest.evaluate(e.patch, 0, 0, &a);
        const double t = e.labels.aperture;
        absError += std::fabs(a - t);
        sumT += t, sumP += a, sumTT += t * t, sumPP += a * a, sumTP += t * a;
    }
    const double cov = sumTP / n - sumT * sumP / n / n;
    const double r = cov / std::sqrt((sumTT / n - sumT * sumT / n / n) * (sumPP / n - sumP * sumP / n / n));
    std::printf("  %s: aperture mean absolute error %.4f eye widths (mean teacher aperture %.3f), r = %.3f over %zu eyes\n", name,
                absError / n, sumT / n, r, data.eyes.size());
}

/// The patches (float32 N x 28 x 40, normalised), every pixel's class (uint8,
/// the teacher's lids and iris or a render's exact classes) and per eye
/// (aperture, iris usable, synthetic) as float32 N x 3.
void writeSamples(const Dataset& data, const std::string& prefix) {
    const std::string rows = std::to_string(kPatchHeight) + ", " + std::to_string(kPatchWidth);
    tools::NpyWriter patches(prefix + "_patches.npy", "<f4", rows), classes(prefix + "_classes.npy", "|u1", rows),
        info(prefix + "_info.npy", "<f4", "3");
    cv::Mat cls(kPatchHeight, kPatchWidth, CV_8U);
    for (const EyeSample& e : data.eyes) {
        for (int y = 0; y < kPatchHeight; ++y)
            for (int x = 0; x < kPatchWidth; ++x) cls.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(pixelClassOf(e, x, y));
        patches.add(e.patch);
        classes.add(cls);
        const float row[3] = {e.labels.aperture, e.iris_usable ? 1.f : 0.f, e.classes.empty() ? 0.f : 1.f};
        info.add(row, sizeof row);
    }
    patches.finish();
    classes.finish();
    info.finish();
    std::printf("wrote %s_{patches,classes,info}.npy: %d eyes\n", prefix.c_str(), patches.rows());
}

/// The corner cascade's eyes: the frame, where the next patch is cut (first
/// the landmarks' corners or jittered ones, then each stage's result) and the
/// true corners.
struct CornerSample {
    int image = 0;  ///< into CornerSet::grays
    Point2 outer, inner, true_outer, true_inner;
    bool mirror = false;
    float iod = 0.f;        ///< the face's inter-ocular distance, frame pixels
    bool jittered = false;  ///< cut about the true corners, not at the landmarks'
};

struct CornerSet {
    std::vector<cv::Mat> grays;
    std::vector<CornerSample> samples;

    /// An eye cut at (outer, inner), kept when its true corners lie within 8 patch pixels
    /// of the canonical ones (else the landmarks are on another face, or on none).
    void add(Point2 outer, Point2 inner, Point2 trueOuter, Point2 trueInner, bool mirror, float iod, bool jittered = false) {
        EyePatch patch;
        if (!cutEyePatch(grays.back(), outer, inner, mirror, patch)) return;
        const Point2 o = toPatch(patch, trueOuter), i = toPatch(patch, trueInner);
        const float t[4] = {o.x - kOuterX, o.y - kCornerY, i.x - kInnerX, i.y - kCornerY};
        if (std::any_of(t, t + 4, [](float v) { return !(std::fabs(v) < 8.f); })) return;
        samples.push_back({static_cast<int>(grays.size()) - 1, outer, inner, trueOuter, trueInner, mirror, iod, jittered});
    }
    /// The eye and its copies jittered about the true corners: the whole eye shifted (sd 6 %
    /// of the eye width) and each corner on its own (sd 4 %), as landmarks err on new faces.
    void addJittered(Point2 trueOuter, Point2 trueInner, bool mirror, float iod, std::mt19937& jitter, int copies) {
        const float w = std::hypot(trueInner.x - trueOuter.x, trueInner.y - trueOuter.y);
        std::normal_distribution<float> shift(0.f, 0.06f * w), own(0.f, 0.04f * w);
        for (int c = 0; c < copies; ++c) {
            const float sx = shift(jitter), sy = shift(jitter);
            add({trueOuter.x + sx + own(jitter), trueOuter.y + sy + own(jitter)},
                {trueInner.x + sx + own(jitter), trueInner.y + sy + own(jitter)}, trueOuter, trueInner, mirror, iod, true);
        }
    }
};

/// 300-W faces of `split` (the 300-W annotators' 68 points): each eye cut where
/// facetrack's landmarks put its corners and, with `jitter`, `copies` times about the annotation.
void addCorners300W(CornerSet& set, tools::Split split, std::mt19937* jitter, int copies) {
    const std::string root = tools::faces300wRoot("");
    Tracker tracker(landmarkModels(), unfiltered());
    FrameResult result;
    for (const auto& image : tools::list300W(root, split)) {
        const cv::Mat bgr = cv::imread(image.image, cv::IMREAD_COLOR);
        if (bgr.empty()) continue;
        const core::Shape2 truth = core::readPts(image.pts);
        const Eigen::Vector2f centroid = truth.rowwise().mean();
        tracker.reset();
        tracker.process(tools::viewOf(bgr), 0.0, result);
        const auto face = std::find_if(result.faces.begin(), result.faces.end(), [&](const FaceResult& f) {
            return f.landmarks && core::contains(f.box, centroid.x(), centroid.y());
        });
        if (face == result.faces.end()) continue;
        set.grays.emplace_back();
        cv::cvtColor(bgr, set.grays.back(), cv::COLOR_BGR2GRAY);
        const auto point = [&](int k) { return Point2{truth(0, k), truth(1, k)}; };
        const float iod = std::hypot(truth(0, 45) - truth(0, 36), truth(1, 45) - truth(1, 36));
        for (const Eye eye : {Eye::Left, Eye::Right}) {
            const int o = outerCorner(eye), i = innerCorner(eye);
            const Landmarks68& l = *face->landmarks;
            set.add(l[static_cast<std::size_t>(o)], l[static_cast<std::size_t>(i)], point(o), point(i), eye == Eye::Left, iod);
            if (jitter) set.addJittered(point(o), point(i), eye == Eye::Left, iod, *jitter, copies);
        }
    }
}

/// Renders (randomTrainingFace, seeds of their own, not eval-gaze's): the true
/// corners are the face model's corners in the landmark convention
/// (FaceModel::landmarkPoints), projected, so that the cascade reads corners in
/// the 300-W annotators' convention on renders as on real faces.
void addCornersSynthetic(CornerSet& set, int renders, unsigned seed, std::mt19937& jitter, int copies) {
    trackTrainingRenders(renders, seed,
                         [&](const tools::SyntheticRenderer& renderer, const tools::SyntheticFace& f, const cv::Mat& image,
                             const tools::ClassMap&, const Landmarks68& l) {
                             set.grays.emplace_back();
                             cv::cvtColor(image, set.grays.back(), cv::COLOR_BGR2GRAY);
                             const Landmarks68 truth = renderer.landmarks(f);
                             const float iod = renderer.interocularPx(f);
                             for (const Eye eye : {Eye::Left, Eye::Right}) {
                                 const auto o = static_cast<std::size_t>(outerCorner(eye)), i = static_cast<std::size_t>(innerCorner(eye));
                                 set.add(l[o], l[i], truth[o], truth[i], eye == Eye::Left, iod);
                                 set.addJittered(truth[o], truth[i], eye == Eye::Left, iod, jitter, copies);
                             }
                         });
}

/// Patches cut where each sample's corners are now, and the targets: the true
/// corners' offsets from the canonical ones, in patch pixels (4 per patch).
void cutCornerPatches(const CornerSet& set, std::vector<cv::Mat>& patches, std::vector<float>& targets) {
    patches.clear();
    targets.clear();
    EyePatch patch;
    for (const CornerSample& s : set.samples) {
        // A later stage's corners can, rarely, collapse: such an eye gets its canonical patch's error as target.
        if (!cutEyePatch(set.grays[static_cast<std::size_t>(s.image)], s.outer, s.inner, s.mirror, patch))
            cutEyePatch(set.grays[static_cast<std::size_t>(s.image)], s.true_outer, s.true_inner, s.mirror, patch);
        const Point2 o = toPatch(patch, s.true_outer), i = toPatch(patch, s.true_inner);
        patches.push_back(patch.pixels.clone());
        targets.insert(targets.end(), {o.x - kOuterX, o.y - kCornerY, i.x - kInnerX, i.y - kCornerY});
    }
}

/// Moves every sample's corners by one stage, as the gaze stage does (refineCorners).
void applyCornerStage(const PatchForest& forest, CornerSet& set) {
    EyePatch patch;
    for (CornerSample& s : set.samples) {
        if (!cutEyePatch(set.grays[static_cast<std::size_t>(s.image)], s.outer, s.inner, s.mirror, patch)) continue;
        const auto corners = refineCorners(forest, patch);
        s.outer = corners[0], s.inner = corners[1];
    }
}

/// The corners' error as eval-gaze reports it, in % of the inter-ocular
/// distance: the midpoint along the eye (it places the eyeball sideways) and
/// each corner's distance from the truth, mean over the set's eyes.
std::pair<double, double> cornerError(const CornerSet& set) {
    double along = 0, each = 0;
    for (const CornerSample& s : set.samples) {
        const float ax = s.true_inner.x - s.true_outer.x, ay = s.true_inner.y - s.true_outer.y;
        const float mx = 0.5f * (s.outer.x + s.inner.x - s.true_outer.x - s.true_inner.x);
        const float my = 0.5f * (s.outer.y + s.inner.y - s.true_outer.y - s.true_inner.y);
        along += std::fabs(mx * ax + my * ay) / std::hypot(ax, ay) / s.iod;
        each += 0.5 *
                (std::hypot(s.outer.x - s.true_outer.x, s.outer.y - s.true_outer.y) +
                 std::hypot(s.inner.x - s.true_inner.x, s.inner.y - s.true_inner.y)) /
                s.iod;
    }
    const double n = static_cast<double>(std::max<std::size_t>(1, set.samples.size()));
    return {100.0 * along / n, 100.0 * each / n};
}

/// The corner cascade: --corner-stages forests, each trained on patches re-cut
/// where the previous stages put the training eyes' corners (cascaded
/// regression). Moves the corners of the `reports` sets (which start where
/// facetrack's landmarks put them) stage by stage and prints their error.
std::vector<PatchForest> trainCornerCascade(CornerSet& train, std::vector<std::pair<const char*, CornerSet*>> reports,
                                            const tools::Args& args, unsigned seed) {
    const int stages = args.integer("--corner-stages", 4);
    if (stages < 1 || static_cast<std::size_t>(stages) > kMaxCornerStages)
        throw Error("--corner-stages must be 1.." + std::to_string(kMaxCornerStages));
    const auto report = [&](const char* when) {
        for (const auto& [name, set] : reports) {
            const auto [along, each] = cornerError(*set);
            std::printf(
                "  %s, %s (%zu eyes): corner midpoint along the eye %.2f %%, corner distance %.2f %% of the inter-ocular distance\n", name,
                when, set->samples.size(), along, each);
        }
        std::fflush(stdout);
    };
    report("landmarks' corners");
    std::vector<PatchForest> cascade;
    std::vector<cv::Mat> patches;
    std::vector<float> targets;
    for (int k = 0; k < stages; ++k) {
        cutCornerPatches(train, patches, targets);
        std::vector<PatchSample> samples;
        for (std::size_t p = 0; p < patches.size(); ++p) samples.push_back({static_cast<int>(p), 0, 0});
        ForestTrainingOptions o;
        o.trees = args.integer("--corner-trees", 48);
        o.depth = args.integer("--corner-depth", 9);
        o.min_leaf = 4;
        o.samples_per_tree = static_cast<int>(samples.size());
        o.search_samples = 6000;
        o.seed = seed + 2 + static_cast<unsigned>(k);
        o.draw = drawPatchTest;
        const auto start = std::chrono::steady_clock::now();
        o.progress = [&](int done, int total) {
            if (done % 8 != 0 && done != total) return;
            std::printf("corner stage %d: tree %d / %d (%.0f s)\n", k + 1, done, total,
                        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
            std::fflush(stdout);
        };
        cascade.push_back(trainPatchForest(patches, samples, targets, 4, o));
        applyCornerStage(cascade.back(), train);
        for (const auto& r : reports) applyCornerStage(cascade.back(), *r.second);
        report(("after stage " + std::to_string(k + 1)).c_str());
    }
    return cascade;
}

/// The iris net's open-map gap on the pixel forest's scale (EyeModelData::open_map_scale): the least-squares
/// line of the forest map's gap on the net's (smoothed as the stage smooths them) over `eyes`, reported
/// there and on `check`.
void calibrateOpenMap(EyeModelData& model, const Dataset& eyes, const Dataset& check, std::ostringstream& provenance) {
    IrisNet net(model.iris_net, "the iris net");
    cv::Mat padded, iris(kClassifiedRegion.rows(), kClassifiedRegion.columns(), CV_32F), netIris = iris.clone();
    cv::Mat forestOpen = iris.clone(), netOpen = iris.clone(), unused = iris.clone();
    struct Gaps {
        std::vector<double> net, forest;
    };
    const auto gaps = [&](const Dataset& data) {
        Gaps g;
        for (const EyeSample& e : data.eyes) {
            classifyByForest(model, e.patch, padded, iris, forestOpen);
            classifyByNet(model, net, {&e.patch, nullptr}, {&netIris, &unused}, {&netOpen, &unused});
            g.net.push_back(openMapGap(netOpen));
            g.forest.push_back(openMapGap(forestOpen));
        }
        return g;
    };
    // Correlation, and the RMS difference of the forest's gap and a * net gap + b.
    const auto report = [](const Gaps& g, double a, double b, const char* name) {
        double raw = 0, mapped = 0;
        for (std::size_t i = 0; i < g.net.size(); ++i) {
            raw += (g.net[i] - g.forest[i]) * (g.net[i] - g.forest[i]);
            mapped += (a * g.net[i] + b - g.forest[i]) * (a * g.net[i] + b - g.forest[i]);
        }
        const double n = static_cast<double>(g.net.size());
        std::printf("  %s: %zu eyes, r = %.3f; RMS against the forest map's gap: %.4f as read, %.4f mapped\n", name, g.net.size(),
                    cli::pearson(g.net, g.forest), std::sqrt(raw / n), std::sqrt(mapped / n));
    };
    const Gaps train = gaps(eyes);
    if (train.net.size() < 100) throw Error("too few eyes to calibrate the iris net's open map");
    const double meanNet = cli::mean(train.net), meanForest = cli::mean(train.forest);
    double sxy = 0, sxx = 0;
    for (std::size_t i = 0; i < train.net.size(); ++i) {
        sxy += (train.net[i] - meanNet) * (train.forest[i] - meanForest);
        sxx += (train.net[i] - meanNet) * (train.net[i] - meanNet);
    }
    model.open_map_scale = static_cast<float>(sxy / sxx);
    model.open_map_offset = static_cast<float>(meanForest - sxy / sxx * meanNet);
    std::printf("open map: the net's gap x reads as the forest's %.3f x %+.3f\n", model.open_map_scale, model.open_map_offset);
    report(train, model.open_map_scale, model.open_map_offset, "training clips");
    report(gaps(check), model.open_map_scale, model.open_map_offset, "held-out clips");
    char line[160];
    std::snprintf(line, sizeof line,
                  "; its open map's gap read as %.3f x %+.3f (least squares onto the pixel forest map's, %zu training-clip eyes)",
                  model.open_map_scale, model.open_map_offset, train.net.size());
    provenance << line;
}

/// The eyes of the clips in ../shared/data/clips, in name order: those named in `holdout` into `held`, the others into
/// `train`, with copies cut at jittered corners when `jitter` is given.
void addClips(Dataset& train, Dataset& held, const std::vector<std::string>& holdout, std::vector<std::string>* trainNames,
              std::mt19937* jitter, const std::function<double()>& seconds) {
    const std::string shared = core::sharedDirectory();
    const auto clipTeacher = tools::readTeacher(shared + "/data/teacher/clips_iris.jsonl");
    std::vector<std::filesystem::path> clips;
    for (const auto& entry : std::filesystem::directory_iterator(shared + "/data/clips"))
        if (entry.path().extension() == ".mp4") clips.push_back(entry.path());
    std::sort(clips.begin(), clips.end());
    for (const auto& path : clips) {
        const std::string name = path.filename().string();
        const bool isHeld = std::find(holdout.begin(), holdout.end(), name) != holdout.end();
        addClip(isHeld ? held : train, shared, clipTeacher, name, isHeld ? nullptr : jitter);
        if (!isHeld && trainNames) trainNames->push_back(name);
        std::printf("clip %s: %s, %zu / %zu eye patches so far (%.0f s)\n", name.c_str(), isHeld ? "held out" : "train", train.eyes.size(),
                    held.eyes.size(), seconds());
    }
}

/// `provenance` without its "; N corner stages ..." part.
std::string withoutCornerStages(const std::string& provenance) {
    static const std::regex stages(R"(; \d+ corner stages[^;]*)");
    return std::regex_replace(provenance, stages, "");
}

}  // namespace

int main(int argc, char** argv) {
    try {
        const tools::Args args(std::vector<std::string>(argv + 1, argv + argc),
                               {"--out", "--holdout", "--pixel-trees", "--pixel-depth", "--aperture-trees", "--aperture-depth", "--seed",
                                "--synthetic", "--samples-out", "--iris-net", "--from", "--corner-trees", "--corner-depth",
                                "--corner-synthetic", "--corner-stages", "--net-map-radius"},
                               {"--help", "--synthetic-pixels", "--corners"});
        if (args.has("--help")) {
            std::puts(kUsage);
            return 0;
        }
        const std::string shared = core::sharedDirectory();
        if (shared.empty()) throw Error("../shared not found: the teacher labels live there");
        const std::string out = args.get("--out", "models/eye_model.ftm");
        const auto holdout = args.has("--holdout") ? tools::splitList(args.get("--holdout")) : tools::clipsOfSplit("heldout");
        const auto start = std::chrono::steady_clock::now();
        const std::function<double()> seconds = [&] {
            return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        };
        // The iris net in place of the pixel forest, its open map calibrated on the clips' eyes.
        const auto addIrisNet = [&](EyeModelData& model, std::ostringstream& provenance) {
            const std::string path = args.get("--iris-net", "");
            model.iris_net = core::readFileBytes(path, "the iris net '" + path + "'");
            model.net_map_radius = args.integer("--net-map-radius", 1);
            if (model.net_map_radius < 0 || model.net_map_radius > kMaxNetMapRadius)
                throw Error("--net-map-radius: 0 to " + std::to_string(kMaxNetMapRadius));
            provenance << "; iris CNN " << std::filesystem::path(path).filename().string()
                       << " (tools/train/eyes/train_iris_net.py) in place of the pixel forest, its maps averaged over "
                       << 2 * model.net_map_radius + 1 << " x " << 2 * model.net_map_radius + 1 << " cells";
            Dataset clips, held;
            addClips(clips, held, holdout, nullptr, nullptr, seconds);
            calibrateOpenMap(model, clips, held, provenance);
        };
        const unsigned seed = static_cast<unsigned>(args.integer("--seed", 1));
        // The corner cascade: 300-W train (eight jittered copies per eye) and renders (four);
        // reported on 300-W validation and on every tenth render, kept back.
        const auto cornerCascade = [&](std::ostringstream& provenance) {
            std::mt19937 cornerJitter(seed);  // its own: the same cascade with --from as in a whole training
            CornerSet train, validation, renders;
            addCorners300W(train, tools::Split::Train, &cornerJitter, 8);
            addCorners300W(validation, tools::Split::Validation, nullptr, 0);
            const int synthetic = args.integer("--corner-synthetic", 12000);
            addCornersSynthetic(renders, synthetic, seed + 2000, cornerJitter, 4);
            CornerSet keptBack;  // every tenth render, its eyes cut at the landmarks only
            std::vector<int> moved(renders.grays.size());
            for (std::size_t g = 0; g < renders.grays.size(); ++g) {
                CornerSet& to = g % 10 == 9 ? keptBack : train;
                to.grays.push_back(renders.grays[g]);
                moved[g] = static_cast<int>(to.grays.size()) - 1;
            }
            for (CornerSample s : renders.samples) {
                const bool back = s.image % 10 == 9;
                if (back && s.jittered) continue;
                s.image = moved[static_cast<std::size_t>(s.image)];
                (back ? keptBack : train).samples.push_back(s);
            }
            std::printf("corner cascade: %zu training eyes (%zu images), %zu validation eyes, %zu kept-back render eyes\n",
                        train.samples.size(), train.grays.size(), validation.samples.size(), keptBack.samples.size());
            std::vector<PatchForest> cascade = trainCornerCascade(
                train, {{"300-W validation", &validation}, {"kept-back renders", &keptBack}}, args, seed);
            provenance << "; " << cascade.size() << " corner stages of " << cascade[0].treeCount() << " trees of depth " << cascade[0].depth
                       << " on the 300-W annotators' eye corners (train split, patches jittered about them) and " << synthetic
                       << " renders' exact corners";
            return cascade;
        };
        if (args.has("--from")) {
            if (!args.has("--iris-net") && !args.has("--corners")) throw Error("--from needs --iris-net or --corners");
            EyeModelData model = readEyeModel(args.get("--from", ""));
            std::ostringstream provenance;
            // A new cascade replaces the old one, and its line in the provenance.
            provenance << (args.has("--corners") ? withoutCornerStages(model.provenance) : model.provenance);
            if (args.has("--iris-net")) addIrisNet(model, provenance);
            if (args.has("--corners")) model.corner_stages = cornerCascade(provenance);
            model.provenance = provenance.str();
            writeEyeModel(out, model);
            std::printf("wrote %s (%.1f kB): %s\n", out.c_str(), std::filesystem::file_size(out) / 1024.0, model.provenance.c_str());
            return 0;
        }

        std::mt19937 jitter(seed);
        Dataset train, validation, heldClips;
        addFaces300W(train, shared, tools::Split::Train, &jitter);
        std::printf("300-W train: %zu eye patches (%.0f s)\n", train.eyes.size(), seconds());
        addFaces300W(validation, shared, tools::Split::Validation, nullptr);
        std::printf("300-W validation: %zu eye patches (%.0f s)\n", validation.eyes.size(), seconds());
        std::vector<std::string> trainClips;
        addClips(train, heldClips, holdout, &trainClips, &jitter, seconds);
        const int synthetic = args.integer("--synthetic", 2500);
        Dataset synth;
        addSynthetic(synth, synthetic, seed + 1000, jitter);
        std::printf("synthetic: %zu eye patches from %d renders (%.0f s)\n", synth.eyes.size(), synthetic, seconds());
        const std::size_t realEyes = train.eyes.size();
        for (auto& e : synth.eyes) train.eyes.push_back(std::move(e));
        if (args.has("--samples-out")) {
            const std::string dir = args.get("--samples-out", "");
            std::filesystem::create_directories(dir);
            writeSamples(train, dir + "/train");
            writeSamples(validation, dir + "/validation");
            writeSamples(heldClips, dir + "/heldout");
            return 0;
        }

        // Pixel classifier.
        // Synthetic eyes teach the aperture forest closed and half-closed eyes at
        // every pose; in the pixel forest they cost accuracy on real eyes
        // (docs/benchmarks.md), so they go there only when asked.
        const PixelSet pixels = pixelSamples(train, 64, seed, args.has("--synthetic-pixels"));
        ForestTrainingOptions po;
        po.trees = args.integer("--pixel-trees", 8);
        po.depth = args.integer("--pixel-depth", 10);
        po.seed = seed;
        po.draw = drawPixelTest;
        std::mutex printing;
        po.progress = [&](int done, int total) {
            std::lock_guard<std::mutex> lock(printing);
            std::printf("pixel forest: tree %d / %d (%.0f s)\n", done, total, seconds());
            std::fflush(stdout);
        };
        EyeModelData model;
        std::printf("pixel forest: %zu pixel samples from %zu patches\n", pixels.samples.size(), pixels.patches.size());
        model.pixels = trainPatchForest(pixels.patches, pixels.samples, pixels.targets, kPixelClasses, po);

        // Aperture regressor: one sample per patch, anchored at the origin;
        // every tenth training eye is kept back to calibrate its output.
        PixelSet apertures;
        std::vector<const EyeSample*> calibration;
        for (std::size_t i = 0; i < train.eyes.size(); ++i) {
            const EyeSample& e = train.eyes[i];
            if (i % 10 == 9) {
                calibration.push_back(&e);
                continue;
            }
            apertures.samples.push_back({static_cast<int>(apertures.patches.size()), 0, 0});
            apertures.patches.push_back(e.patch);
            apertures.targets.push_back(e.labels.aperture);
        }
        ForestTrainingOptions ao;
        ao.trees = args.integer("--aperture-trees", 48);
        ao.depth = args.integer("--aperture-depth", 9);
        ao.min_leaf = 4;
        ao.samples_per_tree = static_cast<int>(apertures.samples.size());
        ao.search_samples = 6000;
        ao.seed = seed + 1;
        ao.draw = drawPatchTest;
        ao.progress = [&](int done, int total) {
            if (done % 8 != 0 && done != total) return;
            std::lock_guard<std::mutex> lock(printing);
            std::printf("aperture forest: tree %d / %d (%.0f s)\n", done, total, seconds());
            std::fflush(stdout);
        };
        model.aperture = trainPatchForest(apertures.patches, apertures.samples, apertures.targets, 1, ao);

        // Openness 0 and 1 in the forest's own output, on the kept-back eyes.
        std::vector<float> open, closed;
        for (const EyeSample* e : calibration) {
            float a;
            model.aperture.evaluate(e->patch, 0, 0, &a);
            (e->labels.aperture < 0.1f ? closed : open).push_back(a);
        }
        if (closed.size() < 10 || open.size() < 100) throw Error("too few closed or open eyes to calibrate the aperture");
        std::sort(open.begin(), open.end());
        std::sort(closed.begin(), closed.end());
        model.open_aperture = open[open.size() / 2];
        model.closed_aperture = closed[closed.size() / 2];

        std::ostringstream provenance;
        provenance << "train_eyes, seed " << seed << ": " << model.pixels.treeCount() << " pixel trees of depth " << model.pixels.depth
                   << ", " << model.aperture.treeCount() << " aperture trees of depth " << model.aperture.depth
                   << "; MediaPipe teacher labels (not ground truth) on 300-W train and the clips";
        for (const auto& c : trainClips) provenance << " " << c;
        provenance << "; " << synthetic << " synthetic renders (" << (args.has("--synthetic-pixels") ? "both forests" : "aperture forest")
                   << "); patches cut with facetrack's own landmarks";
        model.corner_stages = cornerCascade(provenance);
        if (args.has("--iris-net")) addIrisNet(model, provenance);
        model.provenance = provenance.str();
        writeEyeModel(out, model);
        std::printf("wrote %s (%.1f kB) in %.0f s: %s\n", out.c_str(), std::filesystem::file_size(out) / 1024.0, seconds(),
                    model.provenance.c_str());
        std::printf("aperture forest output: open %.3f, closed %.3f (medians over %zu and %zu kept-back eyes)\n", model.open_aperture,
                    model.closed_aperture, open.size(), closed.size());
        Dataset realTrain;
        realTrain.eyes.assign(train.eyes.begin(), train.eyes.begin() + static_cast<std::ptrdiff_t>(realEyes));
        reportPixels(model.pixels, realTrain, "train (teacher)");
        reportPixels(model.pixels, validation, "300-W validation");
        reportPixels(model.pixels, heldClips, "held-out clips");
        reportAperture(model.aperture, realTrain, "train");
        reportAperture(model.aperture, validation, "300-W validation");
        reportAperture(model.aperture, heldClips, "held-out clips");
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "train_eyes: %s\n", e.what());
        return 1;
    }
}
