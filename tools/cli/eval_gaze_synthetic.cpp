#include "eval_gaze_synthetic.hpp"
#include "model/internals.hpp"
#include "stats.hpp"

#include "app/image_view.hpp"
#include "common/synthetic_face.hpp"
#include "gaze/eye_model_data.hpp"
#include "gaze/eye_patch.hpp"
#include "gaze/gaze_fit.hpp"
#include "gaze/iris_net.hpp"

#include "facetrack/facetrack.hpp"

#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <optional>
#include <random>
#include <utility>
#include <vector>

namespace facetrack::cli {

namespace {
constexpr float kDeg = 3.14159265358979f / 180.f;

/// Camera-from-model of a head turned by (yaw, pitch, roll) degrees from
/// facing the camera (yaw > 0 to the subject's left, pitch > 0 down as in HeadPose).
Quaternion headRotation(float yaw, float pitch, float roll) {
    const Eigen::Quaternionf frontal(0.f, 1.f, 0.f, 0.f);
    const Eigen::Quaternionf rest = Eigen::AngleAxisf(yaw * kDeg, Eigen::Vector3f::UnitY()) *
                                    Eigen::AngleAxisf(-pitch * kDeg, Eigen::Vector3f::UnitX()) *
                                    Eigen::AngleAxisf(roll * kDeg, Eigen::Vector3f::UnitZ());
    const Eigen::Quaternionf q = frontal * rest;
    return {q.w(), q.x(), q.y(), q.z()};
}

double angleDeg(const Vec3& a, const Vec3& b) {
    const double d = (a.x * b.x + a.y * b.y + a.z * b.z) /
                     (std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z) * std::sqrt(b.x * b.x + b.y * b.y + b.z * b.z));
    return std::acos(std::clamp(d, -1.0, 1.0)) / kDeg;
}

/// A camera-frame gaze (x right, y down, z away from the camera; a gaze at the camera is -z)
/// as degrees towards the image's right and up.
std::pair<double, double> cameraAngles(const Vec3& d) {
    return {std::atan2(d.x, -d.z) / kDeg, std::atan2(-d.y, std::hypot(d.x, d.z)) / kDeg};
}

/// The angle of the rotation between two orientations, degrees.
double rotationAngleDeg(const Quaternion& a, const Quaternion& b) {
    const double dot = std::fabs(a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z);
    return 2.0 * std::acos(std::min(1.0, dot)) / kDeg;
}

/// The gaze fit alone on a render, with everything else true: the head pose,
/// the eye corners (patches cut at the true landmarks) and the eyeball centres.
/// The pixel maps are the renderer's exact classes or the eye model's
/// classifier's, which separates the classifier's share of the error from
/// the head pose's and landmarks'.
class TrueGeometryFit {
public:
    explicit TrueGeometryFit(const Models& models) : face_(models.face), eyes_(models.eyes), rigs_(EyeRig::both(*models.face)) {
        if (eyes_ && !model::dataOf(*eyes_).iris_net.empty()) net_.emplace(model::dataOf(*eyes_).iris_net, "eye model's iris net");
    }

    /// Angular errors (degrees, camera frame) of both eyes, exact classes first, classifier maps second.
    std::array<std::array<double, 2>, 2> errors(const tools::SyntheticRenderer& renderer, const tools::SyntheticFace& f,
                                                const cv::Mat& image, const cv::Mat& classes) {
        cv::Mat gray;
        cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
        const Landmarks68 landmarks = renderer.landmarks(f);
        const Eigen::Matrix3f R =
            Eigen::Quaternionf(f.rotation.w, f.rotation.x, f.rotation.y, f.rotation.z).normalized().toRotationMatrix();
        const Eigen::Vector3f t(f.translation_mm.x, f.translation_mm.y, f.translation_mm.z);
        core::Camera camera;
        camera.fx = f.fx, camera.fy = f.fy, camera.cx = f.cx, camera.cy = f.cy;
        const std::vector<Vec3> mesh = face_->vertices({}, f.expression);
        std::array<gaze::EyeObservation, 2> exact, classified;
        std::array<const cv::Mat*, 2> patches{};
        std::array<cv::Mat*, 2> iris{}, open{};
        for (std::size_t e = 0; e < 2; ++e) {
            Eye& eye = eyes_seen_[e];
            gaze::cutEyePatch(gray, landmarks, e == 0 ? gaze::Eye::Left : gaze::Eye::Right, eye.patch);
            const Eigen::Vector3f centre = R * gaze::rotationCentre(e == 0 ? face_->leftEyeball() : face_->rightEyeball(),
                                                                    rigs_[e].centre(mesh)) +
                                           t;
            for (int y = 0; y < gaze::kClassifiedRegion.rows(); ++y)
                for (int x = 0; x < gaze::kClassifiedRegion.columns(); ++x) {
                    const Point2 p = gaze::toImage(
                        eye.patch, {static_cast<float>(gaze::kClassifiedRegion.x(x)), static_cast<float>(gaze::kClassifiedRegion.y(y))});
                    const int px = std::clamp(static_cast<int>(std::lround(p.x)), 0, classes.cols - 1);
                    const int py = std::clamp(static_cast<int>(std::lround(p.y)), 0, classes.rows - 1);
                    const int c = classes.at<std::uint8_t>(py, px);
                    eye.exact_iris.at<float>(y, x) = c == gaze::kIris ? 1.f : 0.f;
                    eye.exact_open.at<float>(y, x) = c != gaze::kSkin ? 1.f : 0.f;
                }
            exact[e] = {&eye.patch, &eye.exact_iris, &eye.exact_open, 1.f, centre};
            classified[e] = {&eye.patch, &eye.iris, &eye.open, 1.f, centre};
            patches[e] = &eye.patch.pixels;
            iris[e] = &eye.iris;
            open[e] = &eye.open;
        }
        if (net_) gaze::classifyByNet(model::dataOf(*eyes_), *net_, patches, iris, open);
        else
            for (std::size_t e = 0; e < 2; ++e)
                gaze::classifyByForest(model::dataOf(*eyes_), eyes_seen_[e].patch.pixels, padded_, eyes_seen_[e].iris, eyes_seen_[e].open);
        std::array<std::array<double, 2>, 2> out{};
        const gaze::GazeAngles none{Eigen::Vector2f::Zero(), Eigen::Vector2f::Zero()};
        for (int k = 0; k < 2; ++k) {
            const gaze::GazeAngles a = gaze::fitGaze(k == 0 ? exact : classified, R, camera, none, false);
            for (int e = 0; e < 2; ++e) {
                const Eigen::Vector3f d = R * gaze::gazeDirection(a[static_cast<std::size_t>(e)].x(), a[static_cast<std::size_t>(e)].y());
                out[static_cast<std::size_t>(k)][static_cast<std::size_t>(e)] = angleDeg({d.x(), d.y(), d.z()},
                                                                                         renderer.gazeInCamera(f, e));
            }
        }
        return out;
    }

private:
    struct Eye {
        gaze::EyePatch patch;
        cv::Mat iris = map(), open = map(), exact_iris = map(), exact_open = map();
        static cv::Mat map() { return cv::Mat(gaze::kClassifiedRegion.rows(), gaze::kClassifiedRegion.columns(), CV_32F); }
    };
    std::shared_ptr<const FaceModel> face_;
    std::shared_ptr<const EyeModel> eyes_;
    std::array<EyeRig, 2> rigs_;
    std::optional<gaze::IrisNet> net_;
    std::array<Eye, 2> eyes_seen_;
    cv::Mat padded_;  // scratch for the pixel forest
};

/// A frontal face at inter-ocular distance `iod` px looking at (yaw, pitch), with eyeBlink weights.
tools::SyntheticFace sequenceFace(const FaceModel& model, float iod, float yaw, float pitch, float blinkLeft, float blinkRight,
                                  unsigned seed) {
    tools::SyntheticFace f;
    f.translation_mm = {0.f, 0.f, f.fx * 62.3f / iod};
    f.rotation = headRotation(0, 0, 0);
    f.gaze_deg = {{{yaw - 1.5f, pitch}, {yaw + 1.5f, pitch}}};
    const auto& names = model.expressionNames();
    f.expression.assign(names.size(), 0.f);
    const auto set = [&](const std::string& n, float w) {
        const auto it = std::find(names.begin(), names.end(), n);
        if (it != names.end()) f.expression[static_cast<std::size_t>(it - names.begin())] = w;
    };
    set("eyeBlink_L", blinkLeft);
    set("eyeBlink_R", blinkRight);
    if (pitch < 0) set("eyeLookDown_L", -pitch / 30.f), set("eyeLookDown_R", -pitch / 30.f);
    f.seed = seed;
    return f;
}

/// The targets' scenarios, each a short sequence tracked frame by frame.
void evalSyntheticSequences(const tools::SyntheticRenderer& renderer, Tracker& tracker, const FaceModel& model) {
    FrameResult result;
    int frame = 0;
    const auto step = [&](const tools::SyntheticFace& f) -> const FaceResult* {
        const cv::Mat image = renderer.render(f);
        tracker.process(tools::viewOf(image), frame++ / 30.0, {renderer.faceBox(f)}, result);
        return result.faces.empty() || !result.faces[0].gaze ? nullptr : &result.faces[0];
    };
    const auto blinkOf = [](const FaceResult& f, const char* name) {
        return f.expression ? f.expression->arkit[static_cast<std::size_t>(arkitIndex(name))] : 0.f;
    };
    // Fixation at inter-ocular 80 px, pixel noise only.
    tracker.reset();
    std::vector<double> yaw, pitch, cameraYaw, cameraPitch;
    // After 60 frames of warm-up: the identity calibration (30 frames) and the eyeballs' placement have settled.
    for (int i = 0; i < 110; ++i) {
        const FaceResult* f = step(sequenceFace(model, 80, 8, 4, 0, 0, 100u + static_cast<unsigned>(i)));
        if (f && i >= 60) {
            yaw.push_back(f->gaze->right.yaw_deg), pitch.push_back(f->gaze->right.pitch_deg);
            const auto [x, y] = cameraAngles(f->gaze->right.direction);
            cameraYaw.push_back(x), cameraPitch.push_back(y);
        }
    }
    const auto deviation = [&](const std::vector<double>& v) {
        const double m = mean(v);
        double s = 0;
        for (double x : v) s += (x - m) * (x - m);
        return v.empty() ? std::nan("") : std::sqrt(s / static_cast<double>(v.size()));
    };
    std::printf(
        "  fixation, inter-ocular 80 px, 50 frames of pixel noise after 60 of warm-up: gaze standard deviation yaw %.2f, pitch %.2f deg "
        "(in the camera frame: %.2f, %.2f)\n",
        deviation(yaw), deviation(pitch), deviation(cameraYaw), deviation(cameraPitch));
    // A 20-degree saccade: frames until within 2 degrees of the new gaze's estimate at rest.
    tracker.reset();
    for (int i = 0; i < 10; ++i) step(sequenceFace(model, 80, -10, 0, 0, 0, 200u + static_cast<unsigned>(i)));
    std::vector<double> after;
    for (int i = 0; i < 12; ++i) {
        const FaceResult* f = step(sequenceFace(model, 80, 10, 0, 0, 0, 300u + static_cast<unsigned>(i)));
        after.push_back(f ? f->gaze->right.yaw_deg : std::nan(""));
    }
    const double settled = mean(std::vector<double>(after.end() - 4, after.end()));
    int lag = 0;
    while (lag < static_cast<int>(after.size()) && !(std::fabs(after[static_cast<std::size_t>(lag)] - settled) < 2.0)) ++lag;
    std::printf("  saccade of 20 deg: within 2 deg of the settled estimate after %d frame(s) of lag\n", lag);
    // A blink with the gaze fixed: how far the estimate moves while the eyes are closed, from
    // the last open frame (after they open again it is the fixation's own noise, above).
    tracker.reset();
    double moved = 0, peakBlink = 0;
    std::optional<Vec3> lastOpen;
    for (int i = 0; i < 20; ++i) {
        const float closing = i >= 10 && i < 14 ? (i == 10 || i == 13 ? 0.6f : 1.f) : 0.f;
        const FaceResult* f = step(sequenceFace(model, 80, 6, 2, closing, closing, 400u + static_cast<unsigned>(i)));
        if (!f) continue;
        if (i == 9) lastOpen = f->gaze->right.direction_head;
        if (i >= 11 && i < 13 && lastOpen) moved = std::max(moved, angleDeg(f->gaze->right.direction_head, *lastOpen));
        if (i >= 10 && i < 14) peakBlink = std::max(peakBlink, static_cast<double>(blinkOf(*f, "eyeBlinkRight")));
    }
    std::printf("  blink (2 frames half, 2 fully closed): eyeBlink peak %.2f; closed, the gaze moved %.2f deg from the last open frame\n",
                peakBlink, moved);
    // A head turning at 60 deg/s (2 degrees a frame) from 30 to the left to 30 to the right, the eyes
    // looking ahead of it: the eyeballs' placement must follow the head, not lag it.
    tracker.reset();
    std::vector<double> turning;
    for (int i = 0; i < 40; ++i) {
        tools::SyntheticFace f = sequenceFace(model, 80, 4, 2, 0, 0, 700u + static_cast<unsigned>(i));
        const float yaw = std::clamp(-30.f + 2.f * static_cast<float>(i - 5), -30.f, 30.f);
        f.rotation = headRotation(yaw, 0, 0);
        const FaceResult* r = step(f);
        if (r && i >= 8 && i < 35) turning.push_back(angleDeg(r->gaze->right.direction, renderer.gazeInCamera(f, 1)));
    }
    std::printf("  head turning at 60 deg/s, inter-ocular 80 px: gaze angular error while it turns mean %.2f max %.2f deg\n", mean(turning),
                turning.empty() ? std::nan("") : *std::max_element(turning.begin(), turning.end()));
    // Looking down 25 degrees (the lids follow, as the face model's eyeLookDown shapes make them):
    // from the start, and after 60 frames looking ahead (the open-eye reference then knows the
    // eyes looking ahead, as it does for a user who has been tracked a while).
    std::array<double, 2> downBlink{};
    for (const int ahead : {0, 60}) {
        tracker.reset();
        for (int i = 0; i < ahead + 15; ++i) {
            const float pitch = i < ahead ? 0.f : -25.f;
            const FaceResult* f = step(sequenceFace(model, 80, 0, pitch, 0, 0, 500u + static_cast<unsigned>(i)));
            double& largest = downBlink[ahead == 0 ? 0 : 1];
            if (f && i >= ahead + 5)
                largest = std::max(largest, static_cast<double>(std::max(blinkOf(*f, "eyeBlinkLeft"), blinkOf(*f, "eyeBlinkRight"))));
        }
    }
    std::printf(
        "  looking down 25 deg: largest eyeBlink %.2f from the first frame, %.2f after 60 frames looking ahead (a blink is >= 0.5)\n",
        downBlink[0], downBlink[1]);
    // The same over other faces: inter-ocular 50 / 90 / 120 px, the head turned 0 or 20 degrees,
    // after 20 or 60 frames looking ahead; the largest eyeBlink from the fourth frame looking down.
    int blinks = 0, settings = 0;
    double worst = 0;
    for (const float iod : {50.f, 90.f, 120.f})
        for (const float headYaw : {0.f, 20.f})
            for (const int ahead : {20, 60}) {
                tracker.reset();
                double largest = 0;
                for (int i = 0; i < ahead + 15; ++i) {
                    tools::SyntheticFace f = sequenceFace(model, iod, 0, i < ahead ? 0.f : -25.f, 0, 0, 800u + static_cast<unsigned>(i));
                    f.rotation = headRotation(headYaw, 0, 0);
                    const FaceResult* r = step(f);
                    if (r && i >= ahead + 3)
                        largest = std::max(largest,
                                           static_cast<double>(std::max(blinkOf(*r, "eyeBlinkLeft"), blinkOf(*r, "eyeBlinkRight"))));
                }
                ++settings;
                blinks += largest >= 0.5;
                worst = std::max(worst, largest);
            }
    std::printf(
        "  looking down 25 deg, inter-ocular 50 / 90 / 120 px, head turned 0 / 20 deg, after 20 / 60 frames ahead: "
        "%d of %d read as a blink (largest eyeBlink %.2f)\n",
        blinks, settings, worst);
    // A wink: the left eye closed, the right open.
    tracker.reset();
    double openRight = 1, blinkLeft = 0;
    for (int i = 0; i < 15; ++i) {
        const bool wink = i >= 8;
        const FaceResult* f = step(sequenceFace(model, 80, 0, 0, wink ? 1.f : 0.f, 0, 600u + static_cast<unsigned>(i)));
        if (f && wink)
            openRight = std::min(openRight, static_cast<double>(f->gaze->right.openness)),
            blinkLeft = std::max(blinkLeft, static_cast<double>(blinkOf(*f, "eyeBlinkLeft")));
    }
    std::printf("  wink (left eye closed): left eyeBlink up to %.2f, right eye openness at least %.2f\n", blinkLeft, openRight);
}

}  // namespace

/// A head for the synthetic evaluation: inter-ocular distance 40-120 px, yaw
/// +-30, pitch +-10, roll +-5 degrees, anywhere near the frame's middle;
/// `in(lo, hi)` draws uniformly.
template <class Draw>
tools::SyntheticFace randomHead(Draw& in) {
    tools::SyntheticFace f;
    const float iod = in(40, 120);
    f.translation_mm = {in(-30, 30), in(-20, 20), 0.f};
    f.translation_mm.z = f.fx * 62.3f / iod;
    const float hy = in(-30, 30), hp = in(-10, 10), hr = in(-5, 5);
    f.rotation = headRotation(hy, hp, hr);
    return f;
}

/// A gaze of yaw +-25 and pitch +-20 degrees, the eyes 3 degrees convergent.
template <class Draw>
void lookAtRandom(tools::SyntheticFace& f, Draw& in) {
    const float yaw = in(-25, 25), pitch = in(-20, 20);
    f.gaze_deg = {{{yaw - 1.5f, pitch}, {yaw + 1.5f, pitch}}};
}

/// The same distribution tracked as a video: each head held still for 30
/// frames while the gaze jumps to a new point every 5; the last frame of each
/// fixation after 15 frames of warm-up is measured, so the identity and the
/// eyeballs' placement have settled as they do for a user.
void evalSyntheticTracked(int heads, const tools::SyntheticRenderer& renderer, Tracker& tracker) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> unit(0.f, 1.f);
    const auto in = [&](float lo, float hi) { return lo + (hi - lo) * unit(rng); };
    std::array<std::vector<double>, 4> errors;
    std::vector<double> all;
    FrameResult result;
    for (int h = 0; h < heads; ++h) {
        tools::SyntheticFace f = randomHead(in);
        f.blur_sigma = in(0.f, 1.f);
        const float iod = f.fx * 62.3f / f.translation_mm.z;
        const int bin = std::clamp(static_cast<int>((iod - 40.f) / 20.f), 0, 3);
        tracker.reset();
        for (int i = 0; i < 30; ++i) {
            if (i % 5 == 0) lookAtRandom(f, in);
            f.seed = static_cast<unsigned>(100000 + 30 * h + i);
            tracker.process(tools::viewOf(renderer.render(f)), i / 30.0, {renderer.faceBox(f)}, result);
            if (i < 15 || i % 5 != 4 || result.faces.empty() || !result.faces[0].gaze) continue;
            for (int e = 0; e < 2; ++e) {
                const double error = angleDeg((e == 0 ? result.faces[0].gaze->left : result.faces[0].gaze->right).direction,
                                              renderer.gazeInCamera(f, e));
                errors[static_cast<std::size_t>(bin)].push_back(error);
                all.push_back(error);
            }
        }
    }
    std::printf(
        "  tracked (%d heads held still 30 frames, a new gaze every 5; the last frame of each fixation after 15 frames):"
        " angular error mean %.2f p95 %.2f deg; by inter-ocular 40-60 / 60-80 / 80-100 / 100-120 px, mean",
        heads, mean(all), percentile(all, 0.95));
    for (const auto& e : errors) e.empty() ? std::printf(" -") : std::printf(" %.2f", mean(e));
    std::printf(" deg\n");
}

void evalSyntheticGaze(int renders, const Models& models, const TrackerConfig& config, bool bareFaces) {
    tools::SyntheticRenderer renderer(models.face, !bareFaces);
    // The renderer's camera, as a user who calibrated theirs would give it.
    TrackerConfig known = config;
    known.camera.focal_length_px = tools::SyntheticFace{}.fx;
    Tracker tracker(models, known);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> unit(0.f, 1.f);
    const auto in = [&](float lo, float hi) { return lo + (hi - lo) * unit(rng); };
    const std::array<float, 5> bins = {40, 60, 80, 100, 120};
    std::array<std::vector<double>, 4> errors;
    std::vector<double> yawBias, pitchBias, headErrors, exactErrors, classifiedErrors, cornerErrors, cornerShiftX;
    std::array<std::vector<double>, 2> landmarkErrors,
        refinedErrors;  // per eye: the corner midpoint's error, % of the inter-ocular distance
    TrueGeometryFit trueGeometry(models);
    int failed = 0;
    FrameResult result;
    for (int i = 0; i < renders; ++i) {
        tools::SyntheticFace f = randomHead(in);
        const float iod = f.fx * 62.3f / f.translation_mm.z;
        lookAtRandom(f, in);
        f.blur_sigma = in(0.f, 1.f);
        f.seed = static_cast<unsigned>(i + 1);
        cv::Mat classes;
        const cv::Mat image = renderer.render(f, &classes);
        const auto alone = trueGeometry.errors(renderer, f, image, classes);
        exactErrors.insert(exactErrors.end(), alone[0].begin(), alone[0].end());
        classifiedErrors.insert(classifiedErrors.end(), alone[1].begin(), alone[1].end());
        if (i < 3) cv::imwrite("synthetic_gaze_" + std::to_string(i) + ".png", image);
        tracker.reset();
        tracker.process(tools::viewOf(image), 0.0, {renderer.faceBox(f)}, result);
        if (result.faces.empty() || !result.faces[0].gaze) {
            ++failed;
            continue;
        }
        const int bin = std::clamp(static_cast<int>((iod - bins[0]) / 20.f), 0, 3);
        const FaceResult& face = result.faces[0];
        for (int e = 0; e < 2; ++e) {
            const Vec3 seen = (e == 0 ? face.gaze->left : face.gaze->right).direction, truth = renderer.gazeInCamera(f, e);
            errors[static_cast<std::size_t>(bin)].push_back(angleDeg(seen, truth));
            const auto [seenYaw, seenPitch] = cameraAngles(seen);
            const auto [trueYaw, truePitch] = cameraAngles(truth);
            yawBias.push_back(seenYaw - trueYaw);
            pitchBias.push_back(seenPitch - truePitch);
        }
        if (face.pose) headErrors.push_back(rotationAngleDeg(face.pose->rotation, f.rotation));
        if (face.landmarks) {
            // The eyeballs are placed from the eye corners: how far the tracker's
            // corners' midpoint is from the render's, and what that does to the gaze.
            const Landmarks68 truth = renderer.landmarks(f);
            const float iod = renderer.interocularPx(f);
            cv::Mat gray;
            cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
            for (int e = 0; e < 2; ++e) {
                const gaze::Eye eye = e == 0 ? gaze::Eye::Left : gaze::Eye::Right;
                const auto outer = static_cast<std::size_t>(gaze::outerCorner(eye)),
                           inner = static_cast<std::size_t>(gaze::innerCorner(eye));
                const Landmarks68& l = *face.landmarks;
                // A corner pair's midpoint minus the render's, in frame pixels.
                const auto midpointError = [&](Point2 o, Point2 i) {
                    return Point2{0.5f * (o.x + i.x - truth[outer].x - truth[inner].x),
                                  0.5f * (o.y + i.y - truth[outer].y - truth[inner].y)};
                };
                const Point2 d = midpointError(l[outer], l[inner]);
                cornerErrors.push_back(100.0 * std::hypot(d.x, d.y) / iod);
                cornerShiftX.push_back(d.x / iod);
                landmarkErrors[e].push_back(cornerErrors.back());
                gaze::EyePatch patch, scratch;
                if (!gaze::cutEyePatch(gray, l, eye, patch)) continue;
                const auto refined = gaze::eyeCorners(model::dataOf(*models.eyes), gray, patch, scratch);
                const Point2 r = midpointError(refined[0], refined[1]);
                refinedErrors[e].push_back(100.0 * std::hypot(r.x, r.y) / iod);
            }
        }
    }
    std::vector<double> all;
    std::printf(
        "synthetic (%d renders%s: gaze yaw +-25, pitch +-20 deg; head yaw +-30; noise 2 grey levels, blur 0-1 px; %d without a gaze):\n",
        renders, bareFaces ? " of bare faces, no brows or lips" : "", failed);
    for (int b = 0; b < 4; ++b) {
        const auto& e = errors[static_cast<std::size_t>(b)];
        all.insert(all.end(), e.begin(), e.end());
        if (e.empty()) continue;
        std::printf("  inter-ocular %3.0f-%3.0f px: angular error mean %.2f p95 %.2f deg (%zu eyes)\n", bins[static_cast<std::size_t>(b)],
                    bins[static_cast<std::size_t>(b) + 1], mean(e), percentile(e, 0.95), e.size());
    }
    std::printf("  all: mean %.2f p95 %.2f deg\n", mean(all), percentile(all, 0.95));
    std::printf(
        "  bias, estimated - rendered, camera frame: gaze to the image's right %+.2f, up %+.2f deg; "
        "the single-frame head pose's rotation error mean %.2f p95 %.2f deg\n",
        mean(yawBias), mean(pitchBias), mean(headErrors), percentile(headErrors, 0.95));
    std::printf(
        "  the gaze fit alone, true head pose, eye corners and eyeball centres: on the renderer's exact classes mean %.2f "
        "p95 %.2f deg; on the classifier's maps mean %.2f p95 %.2f deg\n",
        mean(exactErrors), percentile(exactErrors, 0.95), mean(classifiedErrors), percentile(classifiedErrors, 0.95));
    std::printf(
        "  the tracker's eye-corner midpoint (where the eyeball is placed from) is %.2f %% of the inter-ocular distance "
        "from the render's on average; its horizontal error correlates with the gaze's, r = %.2f\n",
        mean(cornerErrors), cornerShiftX.size() == yawBias.size() ? pearson(cornerShiftX, yawBias) : std::nan(""));
    std::printf(
        "  the eye-corner midpoint, subject's left / right eye: landmarks %.2f / %.2f %%, refined by the eye model's corner "
        "cascade (what places the eyeballs) %.2f / %.2f %%\n",
        mean(landmarkErrors[0]), mean(landmarkErrors[1]), mean(refinedErrors[0]), mean(refinedErrors[1]));
    evalSyntheticTracked(std::max(1, renders / 4), renderer, tracker);
    evalSyntheticSequences(renderer, tracker, *models.face);
}

}  // namespace facetrack::cli
