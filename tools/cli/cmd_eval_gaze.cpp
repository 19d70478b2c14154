// facetrack eval-gaze: the gaze stage against the MediaPipe teacher labels
// (../shared/data/teacher: another model's predictions, not ground truth) on
// held-out clips and 300-W images, and on synthetic renders of known gaze.

#include "commands.hpp"
#include "model/internals.hpp"
#include "stats.hpp"

#include "app/image_view.hpp"
#include "common/blendshape_teacher.hpp"
#include "common/expression_labels.hpp"
#include "common/faces300w.hpp"
#include "common/teacher.hpp"
#include "eval_gaze_synthetic.hpp"

#include "gaze/eye_model_data.hpp"
#include "gaze/eye_patch.hpp"

#include "core/box.hpp"
#include "core/environment.hpp"
#include "core/pts.hpp"
#include "facetrack/facetrack.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

namespace facetrack::cli {

namespace {

const char* kUsage =
    R"(usage: facetrack eval-gaze [--clips CLIP,CLIP] [--split validation|test|none] [--synthetic N|0] [--bare-faces] [--labels CSV]
                          [--blendshapes CSV|none] [tracker options]
The gaze stage against MediaPipe's iris and eyelid predictions (teacher labels, not ground truth):
  pupil    pupil centre vs the teacher's iris centre, open eyes only (aperture >= 0.8 of the
           clip's median), over the outer-eye-corner distance: mean and p95
  blink    per clip and eye, closed events (runs with the teacher's aperture below half the clip's
           median): the share with eyeBlink >= 0.5 in the run (recall), and those missed; the share
           of clearly open frames (aperture >= 0.8 of the median) with eyeBlink >= 0.5, and those
           frames; and the clips above the 2 % target. Frames --labels (default
           data/expression_labels.csv) marks closed by eye (blink, eyes_closed, wink_left,
           wink_right) are not open, whatever the teacher reads; nor are frames the blendshape
           teacher reads eyeBlink >= 0.5 (--blendshapes, default ../shared/data/teacher/
           clips_blendshapes.csv; none: the lids alone decide)
  synthetic  N renders of the face model with a textured iris at known gaze (see docs/gaze.md):
           angular error by inter-ocular bin, mean and p95; the mean signed error (bias) and the
           single-frame head pose's error; then the targets' short sequences. The faces have
           painted brows and lips; --bare-faces leaves them out (on bare renders the landmarks,
           trained on photographs, place the brows by guesswork)
--eyes FILE evaluates another eye model than the shipped one (e.g. a candidate from train_eyes).
Defaults: the held-out clips liveportrait_d14_gaze_shifts.mp4 and fgnet_talking_face_franck.mp4,
the 300-W validation split, 400 synthetic renders.)";

/// Per clip and eye (the subject's left, right): the frames labelled closed by eye.
using ClosedByEye = std::map<std::string, std::array<std::set<int>, 2>>;

ClosedByEye readClosedByEye(const std::string& labelsPath) {
    ClosedByEye closed;
    for (const auto& seg : tools::readExpressionLabels(labelsPath)) {
        const bool both = seg.label == "blink" || seg.label == "eyes_closed";
        for (int e = 0; e < 2; ++e) {
            if (!both && seg.label != (e == 0 ? "wink_left" : "wink_right")) continue;
            for (int f = seg.first; f <= seg.last; ++f) closed[seg.clip][static_cast<std::size_t>(e)].insert(f);
        }
    }
    return closed;
}

/// "3-7, 12" from sorted frame numbers.
std::string frameRuns(const std::vector<int>& frames) {
    std::string out;
    for (std::size_t i = 0; i < frames.size();) {
        std::size_t j = i;
        while (j + 1 < frames.size() && frames[j + 1] == frames[j] + 1) ++j;
        out += (out.empty() ? "" : ", ") + std::to_string(frames[i]) + (j > i ? "-" + std::to_string(frames[j]) : "");
        i = j + 1;
    }
    return out;
}

const EyeGaze& eyeOf(const GazeResult& g, gaze::Eye e) { return e == gaze::Eye::Left ? g.left : g.right; }
std::size_t blinkIndex(gaze::Eye e) {
    return static_cast<std::size_t>(arkitIndex(e == gaze::Eye::Left ? "eyeBlinkLeft" : "eyeBlinkRight"));
}
float blinkOf(const ExpressionResult& x, gaze::Eye e) { return x.arkit[blinkIndex(e)]; }

struct ClipFrame {
    std::optional<tools::TeacherRecord> teacher;
    std::optional<tools::BlendshapeScores> blendshapes;  ///< the blendshape teacher's, where it found the face
    std::optional<FaceResult> face;
};

void evalClip(const std::string& shared, const std::string& clip, const std::map<std::string, tools::TeacherRecord>& teacher,
              const std::map<std::string, tools::BlendshapeScores>& blendshapes, const std::array<std::set<int>, 2>& closedByEye,
              const Models& models, const TrackerConfig& config, std::vector<double>& pupilErrors, std::vector<double>& eventsFound,
              std::vector<double>& openAsClosed) {
    cv::VideoCapture video(clipPath(shared, clip));
    if (!video.isOpened()) throw Error("cannot open clip " + clip);
    Tracker tracker(models, config);
    std::vector<ClipFrame> frames;
    cv::Mat bgr;
    FrameResult result;
    for (int f = 0; video.read(bgr); ++f) {
        tracker.process(tools::viewOf(bgr), f / 30.0, result);
        ClipFrame cf;
        const std::string key = tools::teacherKey(std::filesystem::path(clip).filename().string(), f);
        if (const auto t = teacher.find(key); t != teacher.end()) cf.teacher = t->second;
        if (const auto b = blendshapes.find(key); b != blendshapes.end()) cf.blendshapes = b->second;
        if (!result.faces.empty()) cf.face = result.faces[0];
        frames.push_back(std::move(cf));
    }
    std::vector<double> clipPupil;
    long events = 0, found = 0, open = 0, openClosed = 0, labelledClosed = 0, teacherDisagrees = 0, teacherDisagreesClosed = 0;
    std::array<std::vector<int>, 2> misread, missed;  // per eye: open frames read as closed; the frames of closed events not found
    for (const gaze::Eye e : {gaze::Eye::Left, gaze::Eye::Right}) {
        const std::size_t side = e == gaze::Eye::Left ? 0 : 1;
        const std::set<int>& closed = closedByEye[side];
        std::vector<double> apertures;
        for (const auto& f : frames)
            if (f.teacher) apertures.push_back(f.teacher->eye(e).aperture());
        const double median = percentile(apertures, 0.5);
        const auto aperture = [&](std::size_t i) { return frames[i].teacher ? frames[i].teacher->eye(e).aperture() : median; };
        const auto blinks = [&](std::size_t i) {
            const auto& f = frames[i].face;
            return f && f->expression && blinkOf(*f->expression, e) >= 0.5f;
        };
        for (std::size_t i = 0; i < frames.size(); ++i) {
            const auto& f = frames[i];
            if (!f.teacher || !f.face || !f.face->gaze || !f.face->landmarks) continue;
            if (aperture(i) >= 0.8 * median) {
                if (closed.count(static_cast<int>(i))) {
                    ++labelledClosed;
                    continue;
                }
                // Lids the teacher places open, which its own blendshapes read as closed: lowered
                // lids, a squint; the teacher does not call them open, so neither does this measure.
                if (f.blendshapes && (*f.blendshapes)[blinkIndex(e)] >= 0.5f) {
                    ++teacherDisagrees;
                    teacherDisagreesClosed += blinks(i);
                    continue;
                }
                const Landmarks68& l = *f.face->landmarks;
                const double corners = std::hypot(l[45].x - l[36].x, l[45].y - l[36].y);
                const Point2 p = eyeOf(*f.face->gaze, e).pupil_px, c = f.teacher->eye(e).iris_centre;
                clipPupil.push_back(std::hypot(p.x - c.x, p.y - c.y) / corners);
                ++open;
                openClosed += blinks(i);
                if (blinks(i)) misread[side].push_back(static_cast<int>(i));
            }
        }
        // Closed events: runs below half the median; found when eyeBlink >= 0.5 within the run (+-1 frame).
        for (std::size_t i = 0; i < frames.size();) {
            if (!(aperture(i) < 0.5 * median)) {
                ++i;
                continue;
            }
            std::size_t end = i;
            while (end < frames.size() && aperture(end) < 0.5 * median) ++end;
            bool hit = false;
            for (std::size_t k = i > 0 ? i - 1 : 0; k < std::min(end + 1, frames.size()); ++k) hit = hit || blinks(k);
            ++events;
            found += hit;
            for (std::size_t k = i; !hit && k < end; ++k) missed[side].push_back(static_cast<int>(k));
            i = end;
        }
    }
    pupilErrors.insert(pupilErrors.end(), clipPupil.begin(), clipPupil.end());
    if (events > 0) eventsFound.push_back(static_cast<double>(found) / events);
    if (open > 0) openAsClosed.push_back(static_cast<double>(openClosed) / open);
    std::printf(
        "  %-44s pupil error mean %.4f p95 %.4f (%zu open eyes); blink events %ld, found %ld (recall %.2f); "
        "open frames read as closed %.2f %% (%ld of %ld)\n",
        clip.c_str(), mean(clipPupil), percentile(clipPupil, 0.95), clipPupil.size(), events, found,
        events ? static_cast<double>(found) / events : std::nan(""), open ? 100.0 * openClosed / open : 0.0, openClosed, open);
    if (labelledClosed > 0)
        std::printf("    %ld eye frames the teacher reads open are labelled closed by eye: not counted as open\n", labelledClosed);
    if (teacherDisagrees > 0)
        std::printf(
            "    %ld eye frames with the teacher's lids open read eyeBlink >= 0.5 by its blendshapes: not counted as open "
            "(we read %ld of them as closed)\n",
            teacherDisagrees, teacherDisagreesClosed);
    for (const auto& [what, frames] : {std::pair{"read as closed", &misread}, std::pair{"closed events not found", &missed}})
        for (std::size_t e = 0; e < 2; ++e)
            if (!(*frames)[e].empty())
                std::printf("    %s, %s eye: frames %s\n", what, e == 0 ? "left" : "right", frameRuns((*frames)[e]).c_str());
}

void eval300W(const std::string& shared, tools::Split split, const Models& models, const TrackerConfig& config) {
    const std::string root = tools::faces300wRoot("");
    const auto teacher = tools::readTeacher(shared + "/data/teacher/faces300w_iris.jsonl");
    Tracker tracker(models, config);
    std::vector<double> errors, cornerErrors, refinedErrors;
    std::vector<std::pair<const tools::TeacherRecord*, FaceResult>> faces;
    FrameResult result;
    std::vector<double> apertures;
    for (const auto& image : tools::list300W(root, split)) {
        const auto t = teacher.find(std::filesystem::relative(image.image, root).string());
        if (t == teacher.end()) continue;
        const cv::Mat bgr = cv::imread(image.image, cv::IMREAD_COLOR);
        cv::Mat gray;
        tracker.reset();
        tracker.process(tools::viewOf(bgr), 0.0, result);
        const core::Shape2 truth = core::readPts(image.pts);
        const Eigen::Vector2f centroid = truth.rowwise().mean();
        for (const auto& f : result.faces) {
            if (!f.gaze || !f.landmarks) continue;
            const Landmarks68& l = *f.landmarks;
            // The annotated face: the tracked face whose box holds the annotation's centroid (a
            // coarse rule, so faces whose eye landmarks went wrong are counted too).
            if (!core::contains(f.box, centroid.x(), centroid.y())) continue;
            faces.emplace_back(&t->second, f);
            // Where the eyeballs are placed from: the tracker's eye-corner midpoint against the
            // annotation's, along the eye (ground truth: the 300-W annotators' points).
            // Both the landmarks' corners and the eye model's corner cascade's (what places them).
            const double iod = std::hypot(truth(0, 45) - truth(0, 36), truth(1, 45) - truth(1, 36));
            if (gray.empty()) cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
            for (const gaze::Eye e : {gaze::Eye::Left, gaze::Eye::Right}) {
                const int o = gaze::outerCorner(e), i = gaze::innerCorner(e);
                const double ax = truth(0, i) - truth(0, o), ay = truth(1, i) - truth(1, o);
                const auto alongTheEye = [&](Point2 outer, Point2 inner) {
                    const double dx = 0.5 * (outer.x + inner.x - truth(0, o) - truth(0, i)),
                                 dy = 0.5 * (outer.y + inner.y - truth(1, o) - truth(1, i));
                    return 100.0 * std::fabs(dx * ax + dy * ay) / std::hypot(ax, ay) / iod;
                };
                cornerErrors.push_back(alongTheEye(l[o], l[i]));
                gaze::EyePatch patch, scratch;
                if (!gaze::cutEyePatch(gray, l, e, patch)) continue;
                const auto refined = gaze::eyeCorners(model::dataOf(*models.eyes), gray, patch, scratch);
                refinedErrors.push_back(alongTheEye(refined[0], refined[1]));
            }
            for (const gaze::Eye e : {gaze::Eye::Left, gaze::Eye::Right}) apertures.push_back(t->second.eye(e).aperture());
        }
    }
    const double median = percentile(apertures, 0.5);
    std::vector<double> towardsNose, up;
    for (const auto& [t, f] : faces) {
        const Landmarks68& l = *f.landmarks;
        const double corners = std::hypot(l[45].x - l[36].x, l[45].y - l[36].y);
        for (const gaze::Eye e : {gaze::Eye::Left, gaze::Eye::Right}) {
            if (!t->eye(e).in_pts_eye || t->eye(e).aperture() < 0.8 * median) continue;
            const Point2 p = eyeOf(*f.gaze, e).pupil_px, c = t->eye(e).iris_centre;
            errors.push_back(std::hypot(p.x - c.x, p.y - c.y) / corners);
            // The signed difference in the eye's own frame: towards the nose, and up.
            // Image y points down; the left eye's corner axis points the other way along x.
            const Point2 outer = l[static_cast<std::size_t>(gaze::outerCorner(e))],
                         inner = l[static_cast<std::size_t>(gaze::innerCorner(e))];
            const double ux = inner.x - outer.x, uy = inner.y - outer.y, n = std::hypot(ux, uy);
            towardsNose.push_back(((p.x - c.x) * ux + (p.y - c.y) * uy) / n / corners);
            up.push_back(((p.x - c.x) * uy - (p.y - c.y) * ux) / n / corners * (e == gaze::Eye::Left ? -1.0 : 1.0));
        }
    }
    std::printf(
        "300-W %s: pupil error mean %.4f p95 %.4f outer-eye-corner distances (%zu open eyes of %zu faces); "
        "eye-corner midpoint along the eye, against the annotation, mean %.2f %% of the inter-ocular distance "
        "(landmarks), %.2f %% (corner cascade)\n",
        split == tools::Split::Test ? "test" : "validation", mean(errors), percentile(errors, 0.95), errors.size(), faces.size(),
        mean(cornerErrors), mean(refinedErrors));
    std::printf("  our pupil minus the teacher's, mean: towards the nose %+.4f, up %+.4f outer-eye-corner distances\n", mean(towardsNose),
                mean(up));
}

}  // namespace

int runEvalGaze(const std::vector<std::string>& argv) {
    const Args args(argv, trackingOptions({"--clips", "--split", "--synthetic", "--labels", "--blendshapes"}),
                    trackingFlags({"--help", "--bare-faces"}));
    if (args.has("--help")) {
        std::puts(kUsage);
        return 0;
    }
    const std::string shared = core::sharedDirectory();
    if (shared.empty()) throw Error("../shared not found: the teacher labels and clips live there");
    const TrackerConfig config = trackerConfig(args);
    const Models models = trackingModels(args);
    if (!models.eyes) throw Error("no eye model: " + EyeModel::defaultPath() + " not found (or --eyes none)");
    const std::string split = args.get("--split", "validation");
    if (split != "none") tools::parseSplit(split);  // checked before anything opens
    const int synthetic = args.integer("--synthetic", 400);
    if (synthetic < 0 || synthetic > 100000) throw Error("--synthetic must be in 0..100000");

    const auto clips = tools::splitList(args.get("--clips", "liveportrait_d14_gaze_shifts.mp4,fgnet_talking_face_franck.mp4"));
    if (!clips.empty()) {
        const auto teacher = tools::readTeacher(shared + "/data/teacher/clips_iris.jsonl");
        const std::string blendshapesPath = args.get("--blendshapes", shared + "/data/teacher/clips_blendshapes.csv");
        const auto blendshapes = blendshapesPath == "none" ? std::map<std::string, tools::BlendshapeScores>{}
                                                           : tools::readBlendshapeTeacher(blendshapesPath);
        const ClosedByEye closed = readClosedByEye(labelsPath(args));
        std::vector<double> pupil, recall, openClosed;
        std::vector<std::string> overTarget;  // the clips whose open eyes read as closed more often than the 2 % target
        std::printf("clips (teacher: MediaPipe iris + eyelids):\n");
        for (const auto& clip : clips) {
            const auto labelled = closed.find(std::filesystem::path(clip).filename().string());
            const std::size_t before = openClosed.size();
            evalClip(shared, clip, teacher, blendshapes, labelled == closed.end() ? std::array<std::set<int>, 2>{} : labelled->second,
                     models, config, pupil, recall, openClosed);
            if (openClosed.size() > before && openClosed.back() > 0.02) {
                char rate[32];
                std::snprintf(rate, sizeof rate, " %.1f %%", 100.0 * openClosed.back());
                overTarget.push_back(clip + rate);
            }
        }
        std::string named;
        for (const auto& c : overTarget) named += (named.empty() ? ": " : ", ") + c;
        std::printf(
            "clips together: pupil error mean %.4f p95 %.4f; blink recall (mean over clips) %.2f; "
            "open frames read as closed %.2f %%, above 2 %% on %zu of %zu clips%s\n",
            mean(pupil), percentile(pupil, 0.95), mean(recall), 100.0 * mean(openClosed), overTarget.size(), openClosed.size(),
            named.c_str());
    }
    if (split != "none") eval300W(shared, tools::parseSplit(split), models, config);
    if (synthetic > 0) evalSyntheticGaze(synthetic, models, config, args.has("--bare-faces"));
    return 0;
}

}  // namespace facetrack::cli
