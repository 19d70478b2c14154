#include "app/media.hpp"
#include "commands.hpp"

#include "app/image_view.hpp"
#include "common/teacher.hpp"
#include "core/environment.hpp"
#include "data/dense/mediapipe_mesh.hpp"
#include "facetrack/facetrack.hpp"

#include <dlib/image_processing.h>
#include <dlib/image_processing/frontal_face_detector.h>
#include <dlib/opencv.h>

#include <opencv2/imgproc.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>

namespace facetrack::cli {

namespace {

const char* kUsage = R"(usage: facetrack eval-track CLIP... [--frames N] [--size WxH] [--dlib FILE|none] [tracker options]
For each clip, in one run: the share of frames with a face, frames per second (decoding
excluded) and landmark jitter, for facetrack with its filter, facetrack without it (the
same run's raw landmarks), and dlib (HOG detector + 68-point shape_predictor on every frame).
Jitter: RMS over frames and points of the landmarks' second difference in time,
|x(t+1) - 2 x(t) + x(t-1)|, over the outer-eye-corner distance, on frames whose neighbours
have a face too. It counts real motion as well, so compare methods on the same clip.
Teacher (clips of ../shared, whose frames MediaPipe's face mesh labelled: another model's
predictions, not ground truth): at eight points both place alike (eye corners, nose tip,
mouth corners, chin), the mean distance over the teacher's outer-eye-corner distance on
frames where both have a face, and "off": the share of the teacher's frames where the
method has no face or is more than kOff away (following the wrong thing, or lost).
Run on one core for fair fps: taskset -c 0 facetrack eval-track ...)";

using Track = std::vector<std::optional<Landmarks68>>;

/// iBUG landmark -> MediaPipe mesh vertex, at points the two conventions place alike.
constexpr std::array<std::pair<int, int>, 8> kTeacherPoints = {
    {{36, 33}, {39, 133}, {42, 362}, {45, 263}, {30, 1}, {48, 61}, {54, 291}, {8, 152}}};
constexpr double kOff = 0.3;  // outer-eye-corner distances: a face this far off is not followed

/// The teacher's eight points per frame of one clip (empty where it found no face).
using TeacherTrack = std::vector<std::optional<std::array<Point2, kTeacherPoints.size()>>>;

/// The teacher's meshes with each key's row, read once for every clip.
struct Teacher {
    dense::TeacherMeshes meshes;
    std::map<std::string, int> row_of;
};

Teacher readTeacher(const std::string& dir) {
    Teacher t{dense::readTeacherMeshes(dir + "/clips_iris.jsonl", dir + "/clips_mesh.npy"), {}};
    for (int r = 0; r < t.meshes.rows(); ++r) t.row_of.emplace(t.meshes.keys[static_cast<std::size_t>(r)], r);
    return t;
}

TeacherTrack teacherTrack(const Teacher& teacher, const std::string& clip, std::size_t frames) {
    const dense::TeacherMeshes& meshes = teacher.meshes;
    TeacherTrack out(frames);
    for (std::size_t f = 0; f < frames; ++f) {
        const auto row = teacher.row_of.find(tools::teacherKey(clip, static_cast<int>(f)));
        if (row == teacher.row_of.end() || !meshes.found[static_cast<std::size_t>(row->second)]) continue;
        const Eigen::Matrix2Xd mesh = meshes.points(row->second);
        auto& points = out[f].emplace();
        for (std::size_t i = 0; i < kTeacherPoints.size(); ++i) {
            const int v = kTeacherPoints[i].second;
            points[i] = {static_cast<float>(mesh(0, v)), static_cast<float>(mesh(1, v))};
        }
    }
    return out;
}

struct Agreement {
    double mean_error = std::nan("");  ///< outer-eye-corner distances
    double off = std::nan("");         ///< share of the teacher's frames
};

Agreement agreement(const Track& track, const TeacherTrack& teacher) {
    double sum = 0.0;
    long both = 0, labelled = 0, off = 0;
    for (std::size_t f = 0; f < track.size() && f < teacher.size(); ++f) {
        if (!teacher[f]) continue;
        ++labelled;
        if (!track[f]) {
            ++off;
            continue;
        }
        const auto& t = *teacher[f];
        const double eyes = std::hypot(t[0].x - t[3].x, t[0].y - t[3].y);
        double error = 0.0;
        for (std::size_t i = 0; i < kTeacherPoints.size(); ++i) {
            const Point2 p = (*track[f])[kTeacherPoints[i].first];
            error += std::hypot(p.x - t[i].x, p.y - t[i].y);
        }
        error /= static_cast<double>(kTeacherPoints.size()) * std::max(eyes, 1.0);
        sum += error;
        ++both;
        off += error > kOff;
    }
    Agreement a;
    if (both) a.mean_error = sum / static_cast<double>(both);
    if (labelled) a.off = static_cast<double>(off) / static_cast<double>(labelled);
    return a;
}

struct MethodResult {
    Track landmarks;
    double seconds = 0.0;
};

double jitter(const Track& track) {
    double sum = 0.0;
    long count = 0;
    for (std::size_t t = 1; t + 1 < track.size(); ++t) {
        if (!track[t - 1] || !track[t] || !track[t + 1]) continue;
        const auto &a = *track[t - 1], &b = *track[t], &c = *track[t + 1];
        const double eyes = std::hypot(b[36].x - b[45].x, b[36].y - b[45].y);
        if (!(eyes > 1.0)) continue;
        for (std::size_t i = 0; i < b.size(); ++i) {
            const double dx = c[i].x - 2.0 * b[i].x + a[i].x, dy = c[i].y - 2.0 * b[i].y + a[i].y;
            sum += (dx * dx + dy * dy) / (eyes * eyes);
            ++count;
        }
    }
    return count ? std::sqrt(sum / static_cast<double>(count)) : std::nan("");
}

double share(const Track& track) {
    long n = 0;
    for (const auto& l : track) n += l.has_value();
    return track.empty() ? 0.0 : static_cast<double>(n) / static_cast<double>(track.size());
}

void printRow(const char* method, const Track& track, double seconds, const TeacherTrack& teacher) {
    const Agreement a = agreement(track, teacher);
    std::printf("  %-26s %7.1f %% %9.1f %10.4f %10.4f %7.1f %%\n", method, 100.0 * share(track),
                seconds > 0 ? static_cast<double>(track.size()) / seconds : 0.0, jitter(track), a.mean_error, 100.0 * a.off);
}

}  // namespace

int runEvalTrack(const std::vector<std::string>& argv) {
    const Args args(argv, trackingOptions({"--frames", "--size", "--dlib"}), trackingFlags({"--help"}));
    if (args.has("--help")) {
        std::puts(kUsage);
        return 0;
    }
    if (args.positional().empty()) throw Error("give at least one clip (see --help)");
    const TrackerConfig config = trackerConfig(args);
    const auto models = trackingModels(args);
    const int maxFrames = args.integer("--frames", -1);
    const auto size = parseSize(args.get("--size"));
    const std::string dlibPath = args.get("--dlib", "/usr/share/dlib/shape_predictor_68_face_landmarks.dat");
    std::optional<dlib::shape_predictor> predictor;
    if (dlibPath != "none") {
        if (!std::filesystem::exists(dlibPath)) throw Error("no dlib model '" + dlibPath + "' (--dlib none skips dlib)");
        predictor.emplace();
        dlib::deserialize(dlibPath) >> *predictor;
    }
    dlib::frontal_face_detector hog = dlib::get_frontal_face_detector();

    const std::string shared = core::sharedDirectory();
    const std::string teacherDir = shared + "/data/teacher";
    std::optional<Teacher> meshes;
    if (!shared.empty() && std::filesystem::exists(teacherDir + "/clips_mesh.npy")) {
        meshes = readTeacher(teacherDir);
    } else {
        std::puts("(no ../shared/data/teacher: the teacher columns are left empty)");
    }

    std::printf("  %-26s %9s %9s %10s %10s %9s\n", "method", "face", "fps", "jitter", "vs teacher", "off");
    for (const auto& clip : args.positional()) {
        const auto frames = readAllFrames(clip, maxFrames, size);
        // --size letterboxes: the teacher saw the clip's own frames.
        const TeacherTrack teacher = meshes && size.empty()
                                         ? teacherTrack(*meshes, std::filesystem::path(clip).filename().string(), frames.size())
                                         : TeacherTrack{};
        std::printf("%s (%zu frames, %dx%d)\n", clip.c_str(), frames.size(), frames[0].bgr.cols, frames[0].bgr.rows);

        Tracker tracker(models, config);
        Track filtered, raw;
        double seconds = 0.0;
        for (const auto& f : frames) {
            const auto start = std::chrono::steady_clock::now();
            const FrameResult r = tracker.process(tools::viewOf(f.bgr), f.time_s);
            seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            const bool face = !r.faces.empty() && r.faces[0].landmarks;
            filtered.push_back(face ? r.faces[0].landmarks : std::nullopt);
            raw.push_back(face ? r.faces[0].raw.landmarks : std::nullopt);
        }
        printRow(config.filter.enabled ? "facetrack (filtered)" : "facetrack (no filter)", filtered, seconds, teacher);
        if (config.filter.enabled) printRow("facetrack (raw, same run)", raw, seconds, teacher);

        if (predictor) {
            Track dlibTrack;
            double dlibSeconds = 0.0;
            cv::Mat gray;
            for (const auto& f : frames) {
                const auto start = std::chrono::steady_clock::now();
                cv::cvtColor(f.bgr, gray, cv::COLOR_BGR2GRAY);
                const dlib::cv_image<unsigned char> image(gray);
                const auto faces = hog(image);
                std::optional<Landmarks68> points;
                if (!faces.empty()) {
                    const auto shape = (*predictor)(image, faces[0]);
                    Landmarks68 l;
                    for (int i = 0; i < 68; ++i) {
                        l[i] = {static_cast<float>(shape.part(i).x()), static_cast<float>(shape.part(i).y())};
                    }
                    points = l;
                }
                dlibSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
                dlibTrack.push_back(points);
            }
            printRow("dlib HOG + shape_predictor", dlibTrack, dlibSeconds, teacher);
        }
    }
    return 0;
}

}  // namespace facetrack::cli
