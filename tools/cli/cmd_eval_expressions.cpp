// facetrack eval-expressions: the ARKit weights on hand-labelled segments of
// clips (data/expression_labels.csv): the bias on neutral faces, the response
// to each labelled expression, mirror consistency and drift with head yaw.

#include "commands.hpp"
#include "plot.hpp"
#include "stats.hpp"

#include "app/image_view.hpp"
#include "common/blendshape_teacher.hpp"
#include "common/clip_splits.hpp"
#include "common/expression_labels.hpp"
#include "core/environment.hpp"
#include "data/dense/label_table.hpp"
#include "facetrack/facetrack.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

namespace fs = std::filesystem;

namespace facetrack::cli {

namespace {

const char* kUsage = R"(usage: facetrack eval-expressions [CLIP...] [--held-out] [--labels CSV] [--plot PREFIX] [--no-mirror]
                                 [--calibrate-neutral] [--dense CLIPS_CSV] [--no-teacher] [tracker options]
The ARKit-52 weights on hand-labelled segments (default data/expression_labels.csv, clips from
../shared/data/clips; with no CLIP, every clip the labels name; --held-out: only the clips of the
people data/clip_splits.csv holds out of all training, beside the labels):
  neutral   per shape, the mean over neutral segments (eyeLook shapes excluded from the worst)
  response  per labelled expression, the mean of its shapes minus their neutral mean; then the
            same for each of its segments; beside each, the blendshape teacher's on the same frames
  mirror    mean |left shape (image) - right shape (mirrored image)| over all frames
  yaw       per clip, the neutral frames' mean per |yaw| bin (0-10, 10-20, 20-30 deg) minus the clip's
            0-10 deg mean, pooled over the clips; the largest change
            (eyeLook excluded: a turned head's eyes turn back to the camera)
  teacher   MediaPipe Face Landmarker's blendshapes on the same frames (../shared/data/teacher/
            clips_blendshapes.csv: another model's predictions, not ground truth): its neutral, its
            response beside ours, and per shape Pearson r between ours and its over every tracked
            frame of the clips; --no-teacher leaves it out
  dense     with --dense (label_dense's clips.csv): per shape, Pearson r between the tracker and the
            dense teacher labels over every tracked frame of the clips (teacher labels, not truth)
Writes PREFIX_neutral.png (per-shape bars), PREFIX_responses.png (per label and shape, ours beside
the teacher's) and PREFIX_<clip>.png (time series of the expected shapes, the teacher's too,
labelled segments as steps); PREFIX defaults to expressions. --calibrate-neutral calls
Tracker::calibrateNeutral() at the first frame of each clip's first neutral segment; that frame
is left out of the neutral figure.)";

using Segment = tools::LabelledSegment;

/// The ARKit shapes each label should move (squint: either group).
const std::map<std::string, std::vector<std::string>>& expectedShapes() {
    static const std::map<std::string, std::vector<std::string>> shapes = {
        {"smile", {"mouthSmileLeft", "mouthSmileRight"}},
        {"open_mouth", {"jawOpen"}},
        {"pucker", {"mouthPucker"}},
        {"funnel", {"mouthFunnel"}},
        {"brows_up", {"browInnerUp", "browOuterUpLeft", "browOuterUpRight"}},
        {"brows_down", {"browDownLeft", "browDownRight"}},
        {"frown", {"mouthFrownLeft", "mouthFrownRight"}},
        {"press", {"mouthPressLeft", "mouthPressRight"}},
        {"mouth_left", {"mouthLeft"}},
        {"mouth_right", {"mouthRight"}},
        {"sneer", {"noseSneerLeft", "noseSneerRight"}},
        {"squint", {"eyeSquintLeft", "eyeSquintRight", "cheekSquintLeft", "cheekSquintRight"}},
        {"cheek_puff", {"cheekPuff"}},
        {"blink", {"eyeBlinkLeft", "eyeBlinkRight"}},
        {"eyes_closed", {"eyeBlinkLeft", "eyeBlinkRight"}},
        {"wink_left", {"eyeBlinkLeft"}},
        {"wink_right", {"eyeBlinkRight"}},
        {"tongue", {"tongueOut"}},
    };
    return shapes;
}

/// The labels file's segments, each label one eval-expressions knows.
std::vector<Segment> readLabels(const std::string& path) {
    std::vector<Segment> segments = tools::readExpressionLabels(path);
    for (const Segment& seg : segments) {
        if (seg.label != "neutral" && !expectedShapes().count(seg.label))
            throw Error(path + ": unknown label '" + seg.label + "' (" + seg.clip + ")");
    }
    return segments;
}

using Weights = std::array<float, kArkitBlendshapeCount>;

struct Track {
    std::vector<std::optional<Weights>> arkit;
    std::vector<float> yaw;
};

/// `neutralAt` >= 0: Tracker::calibrateNeutral() after that frame.
Track trackClip(const std::string& path, const Models& models, const TrackerConfig& config, bool mirrored, int neutralAt) {
    cv::VideoCapture video(path);
    if (!video.isOpened()) throw Error("cannot open clip " + path);
    Tracker tracker(models, config);
    Track t;
    cv::Mat bgr;
    FrameResult result;
    for (int f = 0; video.read(bgr); ++f) {
        if (mirrored) cv::flip(bgr, bgr, 1);
        tracker.process(tools::viewOf(bgr), f / 30.0, result);
        if (f == neutralAt) tracker.calibrateNeutral();
        if (!result.faces.empty() && result.faces[0].expression) {
            t.arkit.push_back(result.faces[0].expression->arkit);
            t.yaw.push_back(result.faces[0].pose ? result.faces[0].pose->euler_deg.y : 0.f);
        } else {
            t.arkit.push_back(std::nullopt);
            t.yaw.push_back(0.f);
        }
    }
    return t;
}

/// label_dense's clips.csv as ARKit weights, keyed "CLIP#FRAME".
std::map<std::string, Weights> readDenseLabels(const std::string& path, const FaceModel& model) {
    const dense::LabelTable table = dense::readLabelTable(path);
    const auto& native = model.expressionNames();
    std::vector<int> column(native.size());
    for (std::size_t k = 0; k < native.size(); ++k) column[k] = table.column(native[k]);
    std::map<std::string, Weights> out;
    std::vector<float> weights(native.size());
    for (const auto& row : table.rows) {
        for (std::size_t k = 0; k < native.size(); ++k)
            weights[k] = column[k] < 0 ? 0.f : static_cast<float>(row.values[static_cast<std::size_t>(column[k])]);
        out[row.key] = model.toArkit(weights);
    }
    return out;
}

std::size_t idx(const std::string& name) { return static_cast<std::size_t>(arkitIndex(name)); }

/// The name of the ARKit shape mirroring `name` (Left <-> Right).
std::string mirrorName(const std::string& name) {
    for (const auto& [a, b] : {std::pair<std::string, std::string>{"Left", "Right"}, {"Right", "Left"}}) {
        const auto at = name.rfind(a);
        if (at != std::string::npos && at + a.size() == name.size()) return name.substr(0, at) + b;
    }
    if (name == "mouthLeft") return "mouthRight";
    if (name == "mouthRight") return "mouthLeft";
    if (name == "jawLeft") return "jawRight";
    if (name == "jawRight") return "jawLeft";
    return name;
}

void barPlot(const std::string& path, const std::array<double, kArkitBlendshapeCount>& values, const std::string& title) {
    const int w = 1200, h = 420, left = 40, bottom = 150, top = 30;
    cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
    cv::putText(img, title, {left, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    const double scale = (h - bottom - top) / 1.0;
    for (int t = 0; t <= 10; ++t) {
        const int y = h - bottom - static_cast<int>(t * 0.1 * scale);
        cv::line(img, {left, y}, {w - 10, y}, cv::Scalar(230, 230, 230), 1);
        char label[8];
        std::snprintf(label, sizeof label, "%.1f", t * 0.1);
        cv::putText(img, label, {4, y + 4}, cv::FONT_HERSHEY_SIMPLEX, 0.35, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    }
    const double step = static_cast<double>(w - left - 10) / kArkitBlendshapeCount;
    for (int i = 0; i < kArkitBlendshapeCount; ++i) {
        const int x0 = left + static_cast<int>(i * step) + 2, x1 = left + static_cast<int>((i + 1) * step) - 2;
        const int y = h - bottom - static_cast<int>(std::clamp(values[static_cast<std::size_t>(i)], 0.0, 1.0) * scale);
        cv::rectangle(img, {x0, y}, {x1, h - bottom},
                      values[static_cast<std::size_t>(i)] > 0.1 ? cv::Scalar(40, 40, 220) : cv::Scalar(200, 120, 40), -1);
        cv::Mat text(12, 140, CV_8UC3, cv::Scalar(255, 255, 255));
        cv::putText(text, std::string(arkitNames()[static_cast<std::size_t>(i)]), {0, 10}, cv::FONT_HERSHEY_SIMPLEX, 0.35,
                    cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
        cv::Mat rotated;
        cv::rotate(text, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
        const int cx = (x0 + x1) / 2 - 6;
        if (cx >= 0 && cx + 12 <= w) rotated.copyTo(img(cv::Rect(cx, h - bottom + 4, 12, 140)));
    }
    cv::line(img, {left, top}, {w - 10, top}, cv::Scalar(255, 255, 255), 1);
    if (!cv::imwrite(path, img)) throw Error("cannot write '" + path + "'");
}

/// A labels' source (the teacher's, the dense labels) as a track of `frames` frames of `clip`.
Track trackOf(const std::map<std::string, Weights>& labels, const std::string& clip, std::size_t frames) {
    Track t;
    for (std::size_t f = 0; f < frames; ++f) {
        const auto it = labels.find(clip + "#" + std::to_string(f));
        t.arkit.push_back(it == labels.end() ? std::nullopt : std::optional(it->second));
        t.yaw.push_back(0.f);
    }
    return t;
}

/// What the labelled segments show of one source (the tracker, or a teacher on the same frames).
struct SegmentFigures {
    std::array<double, kArkitBlendshapeCount> neutral{};  ///< mean per shape over the neutral frames
    long neutral_frames = 0;
    struct NeutralFrame {
        std::string clip;
        float yaw = 0.f;  ///< |yaw|, degrees: the tracker's, also for a teacher's figures
        Weights weights{};
    };
    std::vector<NeutralFrame> byYaw;
    struct Response {
        long frames = 0;
        std::vector<double> above;  ///< per expected shape: its mean minus its neutral mean
    };
    std::map<std::string, Response> labels;  ///< pooled over a label's segments
    std::vector<Response> segments;          ///< per segment, in the labels' order
};

/// Head-turn invariance on the neutral frames: per clip and |yaw| bin (0-10, 10-20, 20-30 deg, at
/// least 10 frames each), each shape's mean minus the same clip's 0-10 deg mean, pooled over the
/// clips weighted by the turned bin's frames; the largest change over shapes and bins. Within a
/// clip, so that the figure compares a face with itself turned, not one person with another.
struct YawDrift {
    std::array<long, 3> frames{};  ///< neutral frames per bin, all clips
    double change = 0;
    std::string shape = "-";
};

YawDrift yawDrift(const std::vector<SegmentFigures::NeutralFrame>& frames) {
    YawDrift out;
    struct Bin {
        std::array<double, kArkitBlendshapeCount> sum{};
        long frames = 0;
    };
    std::map<std::string, std::array<Bin, 3>> byClip;
    for (const auto& f : frames) {
        if (f.yaw > 30.f) continue;
        const auto bin = static_cast<std::size_t>(std::min(2, static_cast<int>(f.yaw / 10.f)));
        Bin& b = byClip[f.clip][bin];
        for (std::size_t k = 0; k < kArkitBlendshapeCount; ++k) b.sum[k] += f.weights[k];
        ++b.frames, ++out.frames[bin];
    }
    for (std::size_t bin = 1; bin < 3; ++bin) {
        std::array<double, kArkitBlendshapeCount> change{};
        long weight = 0;
        for (const auto& [clip, bins] : byClip) {
            const Bin &frontal = bins[0], &turned = bins[bin];
            if (frontal.frames < 10 || turned.frames < 10) continue;
            for (std::size_t k = 0; k < kArkitBlendshapeCount; ++k)
                change[k] += static_cast<double>(turned.frames) *
                             (turned.sum[k] / static_cast<double>(turned.frames) - frontal.sum[k] / static_cast<double>(frontal.frames));
            weight += turned.frames;
        }
        for (std::size_t k = 0; weight > 0 && k < kArkitBlendshapeCount; ++k) {
            // A turned head's eyes turn back to the camera: the look shapes move by design.
            const std::string name(arkitNames()[k]);
            if (name.rfind("eyeLook", 0) == 0) continue;
            const double c = std::fabs(change[k] / static_cast<double>(weight));
            if (c > out.change) out.change = c, out.shape = name;
        }
    }
    return out;
}

/// The neutral bias and the responses of `tracks` on the labelled segments. Neutral: every frame
/// of every neutral segment but the calibrating ones.
SegmentFigures segmentFigures(const std::vector<Segment>& segments, const std::map<std::string, Track>& tracks,
                              const std::map<std::string, const Segment*>& calibrating) {
    SegmentFigures out;
    for (const auto& s : segments) {
        if (s.label != "neutral" || !tracks.count(s.clip)) continue;
        const Track& t = tracks.at(s.clip);
        for (int f = s.first; f <= s.last && f < static_cast<int>(t.arkit.size()); ++f) {
            const auto& a = t.arkit[static_cast<std::size_t>(f)];
            if (!a) continue;
            if (calibrating.count(s.clip) && f <= calibrating.at(s.clip)->first) continue;  // the calibration frame (and before)
            for (std::size_t k = 0; k < kArkitBlendshapeCount; ++k) out.neutral[k] += (*a)[k];
            out.byYaw.push_back({s.clip, std::fabs(t.yaw[static_cast<std::size_t>(f)]), *a});
            ++out.neutral_frames;
        }
    }
    for (auto& v : out.neutral) v = out.neutral_frames ? v / static_cast<double>(out.neutral_frames) : std::nan("");
    for (const auto& s : segments) {
        SegmentFigures::Response r;
        if (s.label != "neutral" && tracks.count(s.clip)) {
            const auto& shapes = expectedShapes().at(s.label);
            r.above.assign(shapes.size(), 0.0);
            const Track& t = tracks.at(s.clip);
            for (int f = s.first; f <= s.last && f < static_cast<int>(t.arkit.size()); ++f) {
                const auto& a = t.arkit[static_cast<std::size_t>(f)];
                if (!a) continue;
                for (std::size_t k = 0; k < shapes.size(); ++k) r.above[k] += (*a)[idx(shapes[k])];
                ++r.frames;
            }
            SegmentFigures::Response& pooled = out.labels[s.label];
            pooled.above.resize(shapes.size(), 0.0);
            for (std::size_t k = 0; k < shapes.size(); ++k) {
                pooled.above[k] += r.above[k];
                r.above[k] = r.frames ? r.above[k] / static_cast<double>(r.frames) - out.neutral[idx(shapes[k])] : std::nan("");
            }
            pooled.frames += r.frames;
        }
        out.segments.push_back(r);
    }
    for (auto& [label, r] : out.labels) {
        const auto& shapes = expectedShapes().at(label);
        for (std::size_t k = 0; k < shapes.size(); ++k)
            r.above[k] = r.frames ? r.above[k] / static_cast<double>(r.frames) - out.neutral[idx(shapes[k])] : std::nan("");
    }
    return out;
}

/// Prints the neutral bias and, per label and segment, each expected shape's response; with
/// `teacher`, the teacher's on the same frames beside it in brackets.
void printFigures(const std::vector<Segment>& segments, const SegmentFigures& ours, const SegmentFigures* teacher) {
    std::printf("neutral (%ld frames): shapes with a mean above 0.10:", ours.neutral_frames);
    int worst = -1;
    double total = 0;
    int counted = 0;
    for (int k = 0; k < kArkitBlendshapeCount; ++k) {
        const std::string name(arkitNames()[static_cast<std::size_t>(k)]);
        if (name.rfind("eyeLook", 0) == 0) continue;
        const double v = ours.neutral[static_cast<std::size_t>(k)];
        if (worst < 0 || v > ours.neutral[static_cast<std::size_t>(worst)]) worst = k;
        if (v > 0.10) std::printf(" %s %.2f", name.c_str(), v);
        total += v;
        ++counted;
    }
    std::printf("\n  mean over the %d shapes (eyeLook excluded) %.3f; worst: %s %.2f (target: every shape <= 0.10)\n", counted,
                total / counted, std::string(arkitNames()[static_cast<std::size_t>(worst)]).c_str(),
                ours.neutral[static_cast<std::size_t>(worst)]);
    if (teacher) {
        std::printf("  the teacher's neutral on the same frames, above 0.10:");
        for (std::size_t k = 0; k < kArkitBlendshapeCount; ++k)
            if (teacher->neutral[k] > 0.10 && std::string(arkitNames()[k]).rfind("eyeLook", 0) != 0)
                std::printf(" %s %.2f", std::string(arkitNames()[k]).c_str(), teacher->neutral[k]);
        std::printf("\n");
    }
    auto shapesLine = [&](const std::vector<std::string>& shapes, const std::vector<double>& a, const std::vector<double>* b, bool named) {
        for (std::size_t k = 0; k < shapes.size(); ++k) {
            std::printf(named ? " %s %+.2f" : "%.0s %+.2f", shapes[k].c_str(), a[k]);
            if (b) std::printf(" (%+.2f)", (*b)[k]);
        }
        std::printf("\n");
    };
    std::printf("response (segment mean - neutral mean; target >= 0.3%s):\n", teacher ? "; the teacher's in brackets" : "");
    for (const auto& [label, shapes] : expectedShapes()) {
        const auto it = ours.labels.find(label);
        if (it == ours.labels.end() || it->second.frames == 0) {
            std::printf("  %-11s no labelled frames\n", label.c_str());
            continue;
        }
        std::printf("  %-11s (%4ld frames):", label.c_str(), it->second.frames);
        shapesLine(shapes, it->second.above, teacher ? &teacher->labels.at(label).above : nullptr, true);
        // Each segment on its own: a label's pooled figure hides segments that show it weakly.
        for (std::size_t i = 0; i < segments.size(); ++i) {
            const Segment& s = segments[i];
            if (s.label != label || ours.segments[i].frames == 0) continue;
            std::printf("    %s %d-%d:", fs::path(s.clip).stem().string().c_str(), s.first, s.last);
            shapesLine(shapes, ours.segments[i].above, teacher ? &teacher->segments[i].above : nullptr, false);
        }
    }
}

/// Per label and expected shape, our response beside the teacher's: grouped bars.
void responsePlot(const std::string& path, const SegmentFigures& ours, const SegmentFigures& teacher) {
    std::vector<std::pair<std::string, std::pair<double, double>>> bars;
    for (const auto& [label, r] : ours.labels) {
        if (r.frames == 0) continue;
        const auto& shapes = expectedShapes().at(label);
        for (std::size_t k = 0; k < shapes.size(); ++k)
            bars.push_back({label + ": " + shapes[k], {r.above[k], teacher.labels.at(label).above[k]}});
    }
    const int left = 50, bottom = 190, top = 40, step = 28;
    const int w = left + step * static_cast<int>(bars.size()) + 20, h = 520;
    cv::Mat img(h, std::max(w, 400), CV_8UC3, cv::Scalar(255, 255, 255));
    cv::putText(img, "response above neutral per label and shape: ours (blue) beside the blendshape teacher's (orange)", {left, 22},
                cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    const double scale = (h - bottom - top) / 1.2;  // -0.2 .. 1.0
    const int zero = h - bottom - static_cast<int>(0.2 * scale);
    for (int t = -2; t <= 10; ++t) {
        const int y = zero - static_cast<int>(t * 0.1 * scale);
        cv::line(img, {left, y}, {img.cols - 10, y}, t == 0 ? cv::Scalar(0, 0, 0) : cv::Scalar(230, 230, 230), 1);
        if (t % 2 == 0) {
            char label[8];
            std::snprintf(label, sizeof label, "%+.1f", t * 0.1);
            cv::putText(img, label, {4, y + 4}, cv::FONT_HERSHEY_SIMPLEX, 0.35, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
        }
    }
    const int target = zero - static_cast<int>(0.3 * scale);
    cv::line(img, {left, target}, {img.cols - 10, target}, cv::Scalar(60, 180, 60), 1);
    for (std::size_t i = 0; i < bars.size(); ++i) {
        const int x = left + step * static_cast<int>(i) + 3;
        const auto [a, b] = bars[i].second;
        auto bar = [&](int x0, double v, const cv::Scalar& colour) {
            if (!std::isfinite(v)) return;
            const int y = zero - static_cast<int>(std::clamp(v, -0.2, 1.0) * scale);
            cv::rectangle(img, {x0, std::min(y, zero)}, {x0 + 10, std::max(y, zero)}, colour, -1);
        };
        bar(x, a, cv::Scalar(200, 110, 30));
        bar(x + 11, b, cv::Scalar(40, 140, 240));
        cv::Mat text(12, bottom - 10, CV_8UC3, cv::Scalar(255, 255, 255));
        cv::putText(text, bars[i].first, {0, 10}, cv::FONT_HERSHEY_SIMPLEX, 0.35, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
        cv::Mat rotated;
        cv::rotate(text, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
        rotated.copyTo(img(cv::Rect(x + 5, h - bottom + 6, 12, bottom - 10)));
    }
    if (!cv::imwrite(path, img)) throw Error("cannot write '" + path + "'");
}

/// The output's jitter on the neutral segments, per group of shapes: the mean |w_t - w_(t-1)| over
/// consecutive neutral frames (a relaxed face holds still; what moves is noise).
void printJitter(const std::vector<Segment>& segments, const std::map<std::string, Track>& tracks) {
    const std::vector<std::pair<std::string, std::vector<std::string>>> groups = {{"brows", {"browDown", "browInnerUp", "browOuterUp"}},
                                                                                  {"eyes", {"eyeBlink", "eyeSquint", "eyeWide"}},
                                                                                  {"mouth and jaw", {"mouth", "jaw"}},
                                                                                  {"cheeks and nose", {"cheek", "nose"}}};
    std::printf("jitter on the neutral segments, mean |frame-to-frame change|:");
    for (const auto& [group, prefixes] : groups) {
        double sum = 0.0;
        long n = 0;
        for (const auto& s : segments) {
            if (s.label != "neutral" || !tracks.count(s.clip)) continue;
            const Track& t = tracks.at(s.clip);
            for (int f = s.first + 1; f <= s.last && f < static_cast<int>(t.arkit.size()); ++f) {
                const auto &a = t.arkit[static_cast<std::size_t>(f - 1)], &b = t.arkit[static_cast<std::size_t>(f)];
                if (!a || !b) continue;
                for (std::size_t k = 0; k < kArkitBlendshapeCount; ++k) {
                    const std::string name(arkitNames()[k]);
                    if (std::none_of(prefixes.begin(), prefixes.end(), [&](const std::string& p) { return name.rfind(p, 0) == 0; }))
                        continue;
                    sum += std::fabs((*b)[k] - (*a)[k]);
                    ++n;
                }
            }
        }
        std::printf(" %s %.4f", group.c_str(), n ? sum / static_cast<double>(n) : std::nan(""));
    }
    std::printf("\n");
}

/// Per shape, Pearson r between the tracker and `labels` over every frame both have, printed
/// (eyeLook left out); the targets marked *.
void printAgreement(const char* what, const std::vector<std::string>& clips, const std::map<std::string, Track>& tracks,
                    const std::map<std::string, Weights>& labels, const std::vector<std::string>& targets) {
    std::array<std::vector<double>, kArkitBlendshapeCount> ours, theirs;
    for (const auto& clip : clips) {
        const Track& t = tracks.at(clip);
        for (std::size_t f = 0; f < t.arkit.size(); ++f) {
            const auto it = labels.find(clip + "#" + std::to_string(f));
            if (!t.arkit[f] || it == labels.end()) continue;
            for (std::size_t k = 0; k < kArkitBlendshapeCount; ++k) {
                ours[k].push_back((*t.arkit[f])[k]);
                theirs[k].push_back(it->second[k]);
            }
        }
    }
    std::printf("%s (%zu frames), Pearson r per shape (target >= 0.8 for the marked *):\n ", what, ours[0].size());
    int column = 0;
    for (std::size_t k = 0; k < kArkitBlendshapeCount; ++k) {
        const std::string name(arkitNames()[k]);
        if (name.rfind("eyeLook", 0) == 0) continue;
        const bool target = std::find(targets.begin(), targets.end(), name) != targets.end();
        std::printf(" %s%s %+.2f", target ? "*" : "", name.c_str(), pearson(ours[k], theirs[k]));
        if (++column % 6 == 0) std::printf("\n ");
    }
    std::printf("\n  (nan: one side is constant, e.g. a shape neither estimates)\n");
}

}  // namespace

int runEvalExpressions(const std::vector<std::string>& argv) {
    const Args args(argv, trackingOptions({"--labels", "--plot", "--dense"}),
                    trackingFlags({"--help", "--no-mirror", "--calibrate-neutral", "--held-out", "--no-teacher"}));
    if (args.has("--help")) {
        std::puts(kUsage);
        return 0;
    }
    const std::string shared = core::sharedDirectory();
    if (shared.empty()) throw Error("../shared not found: the clips live there");
    const std::string labels = labelsPath(args);
    const auto segments = readLabels(labels);
    std::vector<std::string> clips = args.positional();
    if (clips.empty()) {
        const std::vector<std::string> heldOut = args.has("--held-out")
                                                     ? tools::clipsOfSplit("heldout",
                                                                           (fs::path(labels).parent_path() / "clip_splits.csv").string())
                                                     : std::vector<std::string>{};
        for (const auto& s : segments)
            if (std::find(clips.begin(), clips.end(), s.clip) == clips.end() &&
                (heldOut.empty() || std::find(heldOut.begin(), heldOut.end(), s.clip) != heldOut.end()))
                clips.push_back(s.clip);
        if (args.has("--held-out")) std::printf("the held-out people's labelled clips (%zu)\n", clips.size());
    }
    const TrackerConfig config = trackerConfig(args);
    const Models models = trackingModels(args);
    const std::string prefix = args.get("--plot", "expressions");
    std::map<std::string, Weights> dense;
    if (args.has("--dense")) dense = readDenseLabels(args.get("--dense"), *models.face);
    std::map<std::string, Weights> teacher;
    if (!args.has("--no-teacher")) teacher = tools::readBlendshapeTeacher(shared + "/data/teacher/clips_blendshapes.csv");
    // A clip is a name in ../shared/data/clips (as the labels name it) or a path to one.
    std::map<std::string, std::string> paths;
    for (auto& clip : clips) {
        const fs::path given(clip);
        paths[given.filename().string()] = clipPath(shared, clip);
        clip = given.filename().string();
    }

    // With --calibrate-neutral, each clip's first neutral segment's first frame calibrates, and is
    // left out of the neutral figure (the rest of the segment counts: a relaxed face stays relaxed).
    const bool calibrate = args.has("--calibrate-neutral");
    std::map<std::string, const Segment*> calibrating;
    if (calibrate) {
        for (const auto& s : segments)
            if (s.label == "neutral" && !calibrating.count(s.clip)) calibrating[s.clip] = &s;
    }
    std::map<std::string, Track> tracks, mirrored;
    for (const auto& clip : clips) {
        const int at = calibrating.count(clip) ? calibrating[clip]->first : -1;
        tracks[clip] = trackClip(paths[clip], models, config, false, at);
        if (!args.has("--no-mirror")) mirrored[clip] = trackClip(paths[clip], models, config, true, at);
    }
    if (calibrate)
        std::printf("neutral calibrated at the first frame of each clip's first neutral segment (%zu clips)\n", calibrating.size());
    const SegmentFigures neutralFigures = segmentFigures(segments, tracks, calibrating);
    std::optional<SegmentFigures> teacherFigures;
    if (!teacher.empty()) {
        std::map<std::string, Track> teacherTracks;
        for (const auto& clip : clips) {
            teacherTracks[clip] = trackOf(teacher, clip, tracks[clip].arkit.size());
            teacherTracks[clip].yaw = tracks[clip].yaw;  // binned by the tracker's yaw, as ours
        }
        teacherFigures = segmentFigures(segments, teacherTracks, calibrating);
    }
    printFigures(segments, neutralFigures, teacherFigures ? &*teacherFigures : nullptr);
    printJitter(segments, tracks);
    const auto& neutral = neutralFigures.neutral;
    // Mirror consistency: the mirrored clip's right shape against the clip's left shape.
    if (!args.has("--no-mirror")) {
        double sum = 0;
        long n = 0;
        for (const auto& clip : clips) {
            const Track &a = tracks[clip], &b = mirrored[clip];
            for (std::size_t f = 0; f < std::min(a.arkit.size(), b.arkit.size()); ++f) {
                if (!a.arkit[f] || !b.arkit[f]) continue;
                for (int k = 0; k < kArkitBlendshapeCount; ++k) {
                    const std::string name(arkitNames()[static_cast<std::size_t>(k)]);
                    const std::string other = mirrorName(name);
                    if (other == name) continue;
                    sum += std::fabs((*a.arkit[f])[static_cast<std::size_t>(k)] - (*b.arkit[f])[idx(other)]);
                    ++n;
                }
            }
        }
        std::printf("mirror: mean |L(image) - R(mirrored image)| %.3f over %ld shape-frames of the sided shapes (target <= 0.05)\n",
                    n ? sum / static_cast<double>(n) : std::nan(""), n);
    }
    const YawDrift drift = yawDrift(neutralFigures.byYaw);
    std::printf(
        "yaw: neutral frames with |yaw| 0-10 / 10-20 / 20-30 deg: %ld / %ld / %ld; largest change of a shape's mean "
        "from a clip's 0-10 deg frames %.2f (%s",
        drift.frames[0], drift.frames[1], drift.frames[2], drift.change, drift.shape.c_str());
    if (teacherFigures) {
        const YawDrift t = yawDrift(teacherFigures->byYaw);
        std::printf("; the teacher's on the same frames %.2f, %s", t.change, t.shape.c_str());
    }
    std::printf(")\n");

    // The targets the per-frame agreement is read against.
    const std::vector<std::string> rTargets = {"jawOpen",     "mouthSmileLeft", "mouthSmileRight", "mouthPucker",    "mouthFunnel",
                                               "browInnerUp", "browDownLeft",   "browDownRight",   "mouthPressLeft", "mouthPressRight"};
    if (!teacher.empty()) {
        printAgreement("the blendshape teacher (MediaPipe's predictions, not truth)", clips, tracks, teacher, rTargets);
        responsePlot(prefix + "_responses.png", neutralFigures, *teacherFigures);
    }
    if (args.has("--dense")) {
        printAgreement("dense teacher labels", clips, tracks, dense, rTargets);
        std::map<std::string, Track> labelTracks;  // are they a fair target on the labelled segments?
        for (const auto& clip : clips) labelTracks[clip] = trackOf(dense, clip, tracks[clip].arkit.size());
        std::printf("the dense teacher labels themselves on the labelled segments:\n");
        printFigures(segments, segmentFigures(segments, labelTracks, {}), nullptr);
    }

    barPlot(prefix + "_neutral.png", neutral, "mean ARKit weight on the labelled neutral segments");
    for (const auto& clip : clips) {
        LinePlot plot;
        plot.title = clip + ": expected shapes, labelled segments as steps";
        plot.x_label = "frame";
        plot.y_label = "weight";
        const Track& t = tracks[clip];
        plot.x_max = static_cast<double>(t.arkit.size());
        plot.x_tick_format = "%.0f";
        std::map<std::string, bool> used;
        for (const auto& s : segments) {
            if (s.clip != clip) continue;
            PlotSeries step{s.label + " (labelled)", {{s.first, 0.0}, {s.first, 1.0}, {s.last, 1.0}, {s.last, 0.0}}};
            plot.series.push_back(step);
            if (s.label == "neutral") continue;
            for (const auto& shape : expectedShapes().at(s.label)) {
                if (used[shape]) continue;
                used[shape] = true;
                PlotSeries line{shape, {}};
                for (std::size_t f = 0; f < t.arkit.size(); ++f)
                    if (t.arkit[f]) line.points.push_back({static_cast<double>(f), (*t.arkit[f])[idx(shape)]});
                plot.series.push_back(line);
                if (!teacher.empty()) {
                    PlotSeries taught{shape + " (teacher)", {}};
                    for (std::size_t f = 0; f < t.arkit.size(); ++f) {
                        const auto it = teacher.find(clip + "#" + std::to_string(f));
                        if (it != teacher.end()) taught.points.push_back({static_cast<double>(f), it->second[idx(shape)]});
                    }
                    plot.series.push_back(taught);
                }
                if (dense.empty()) continue;
                PlotSeries labelled{shape + " (dense labels)", {}};
                for (std::size_t f = 0; f < t.arkit.size(); ++f) {
                    const auto it = dense.find(clip + "#" + std::to_string(f));
                    if (it != dense.end()) labelled.points.push_back({static_cast<double>(f), it->second[idx(shape)]});
                }
                plot.series.push_back(labelled);
            }
        }
        std::string name = clip.substr(0, clip.rfind('.'));
        writeLinePlot(prefix + "_" + name + ".png", plot);
    }
    std::printf("plots: %s_neutral.png and %s_<clip>.png\n", prefix.c_str(), prefix.c_str());
    return 0;
}

}  // namespace facetrack::cli
