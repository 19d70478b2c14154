#include "track/tracker_core.hpp"

#include "core/box.hpp"
#include "core/image.hpp"
#include "facetrack/error.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace facetrack::track {

namespace {

constexpr int kVerifyCropWidth = 128;  // px: the verification crop is detected at this width
constexpr float kSameFaceIou = 0.3f;   // a detection overlapping a followed face this much is that face
// A followed face agrees with a detection when the detection's centre lies in
// the middle of the face's box: within a quarter of its width of its centre
// across, 0.4 of its height up or down. On the clips, well-followed faces put
// YuNet's centre within 0.05 widths across and 0.08-0.27 heights up (its box
// takes in the forehead); on 2,559 300-W photographs, within 0.14 across below
// 30 deg of yaw and 0.20 at 30-45 deg, 0.03-0.30 up. A fit that slid onto the
// side of a fast-turning head put it 0.27-0.50 widths across.
constexpr float kAgreeAcross = 0.25f, kAgreeUpDown = 0.4f;
// A face a stage doubts must agree across more closely: just beyond where
// YuNet's centre lies for faces followed well (0.05 widths on the clips; p99
// 0.09 on 300-W photographs below 30 deg of yaw). A fit that slid onto the side
// of a face moving fast, its shape shrunk, put it 0.16 widths across and stayed
// there for seven frames under the wider tolerance (d12, docs/benchmarks.md).
constexpr float kAgreeAcrossInDoubt = 0.1f;

// What the stages followed is checked against what they followed a frame ago:
// the face's box, 16 px square, standardised; correlation below kAlike is
// doubtful. On the clips well-followed faces give >= 0.83 (p1 0.87-0.98 per
// clip); a landmark search that stayed behind a fast-moving face, 0.39.
constexpr int kAppearanceSide = 16;
constexpr double kAlike = 0.7;

/// The face's box in `gray` as kAppearanceSide x kAppearanceSide cell means
/// (up to 4 x 4 samples a cell), zero mean and unit RMS, into `out` (no
/// allocation once it has the size). False when the box leaves the frame or
/// is flat.
bool appearanceOf(const cv::Mat& gray, const Box& box, std::vector<float>& out) {
    const cv::Rect region = cv::Rect(cvFloor(box.x0), cvFloor(box.y0), cvCeil(box.width()), cvCeil(box.height())) &
                            cv::Rect(0, 0, gray.cols, gray.rows);
    if (region.width < kAppearanceSide || region.height < kAppearanceSide) return false;
    out.resize(kAppearanceSide * kAppearanceSide);
    const double cellW = static_cast<double>(region.width) / kAppearanceSide, cellH = static_cast<double>(region.height) / kAppearanceSide;
    const int stepX = std::max(1, static_cast<int>(cellW / 4)), stepY = std::max(1, static_cast<int>(cellH / 4));
    double sum = 0.0, squares = 0.0;
    for (int cy = 0; cy < kAppearanceSide; ++cy) {
        const int y0 = region.y + static_cast<int>(cy * cellH), y1 = region.y + static_cast<int>((cy + 1) * cellH);
        for (int cx = 0; cx < kAppearanceSide; ++cx) {
            const int x0 = region.x + static_cast<int>(cx * cellW), x1 = region.x + static_cast<int>((cx + 1) * cellW);
            int total = 0, count = 0;
            for (int y = y0; y < y1; y += stepY) {
                const std::uint8_t* row = gray.ptr<std::uint8_t>(y);
                for (int x = x0; x < x1; x += stepX, ++count) total += row[x];
            }
            const double mean = static_cast<double>(total) / std::max(count, 1);
            out[cy * kAppearanceSide + cx] = static_cast<float>(mean);
            sum += mean;
            squares += mean * mean;
        }
    }
    const double n = static_cast<double>(out.size()), mean = sum / n, deviation = std::sqrt(std::max(0.0, squares / n - mean * mean));
    if (!(deviation > 1.0)) return false;
    for (float& v : out) v = static_cast<float>((v - mean) / deviation);
    return true;
}

/// Normalised cross-correlation of two appearances: 1 alike, 0 unrelated.
double alike(const std::vector<float>& a, const std::vector<float>& b) {
    double sum = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) sum += static_cast<double>(a[i]) * b[i];
    return sum / static_cast<double>(a.size());
}

bool agrees(const Box& followed, const Box& detection, float across) {
    const float dx = 0.5f * (detection.x0 + detection.x1 - followed.x0 - followed.x1);
    const float dy = 0.5f * (detection.y0 + detection.y1 - followed.y0 - followed.y1);
    return std::abs(dx) <= across * followed.width() && std::abs(dy) <= kAgreeUpDown * followed.height();
}

}  // namespace

TrackerCore::TrackerCore(std::unique_ptr<FaceDetector> detector, pipeline::StageList stages, const LifecycleSettings& settings)
    : detector_(std::move(detector)),
      stages_(std::move(stages)),
      settings_(settings),
      last_time_(std::numeric_limits<double>::quiet_NaN()) {
    if (!detector_) throw Error("Tracker: no face detector");
    names_ = {"detect", "verify"};
    // The contracts: each available stage's reads must be written by an
    // available stage before it; it is told what those provide.
    pipeline::Upstream upstream;
    for (const auto& stage : stages_) {
        if (!stage) throw Error("Tracker: a null stage in the stage list");
        StageInfo info = stage->info();
        if (info.available) {
            const pipeline::Fields missing = stage->contract().reads - upstream.written;
            if (missing.empty()) {
                stage->connect(upstream);
                pipeline::provide(stage->contract(), upstream);
            } else {
                info = {info.name, false, "not available: needs " + missing.names() + ", which no stage before it writes"};
            }
        }
        names_.push_back(info.name);
        infos_.push_back(std::move(info));
    }
    expressions_ = upstream.expressions;
    ms_.assign(names_.size(), 0.0);
    ran_.assign(names_.size(), false);
    tracks_.reserve(static_cast<std::size_t>(settings_.max_faces));
}

std::vector<StageInfo> TrackerCore::stages() const {
    std::vector<StageInfo> out;
    out.push_back({"detect", true,
                   detector_->kind() + " (" + detector_->modelPath() + "), while fewer than " + std::to_string(settings_.max_faces) +
                       " face(s) are followed"});
    out.push_back(settings_.verify_interval > 0
                      ? StageInfo{"verify", true,
                                  "the detector on a crop around each followed face, every " + std::to_string(settings_.verify_interval) +
                                      " frames and when a face is in doubt"}
                      : StageInfo{"verify", false, "off (TrackerConfig::verify_interval is 0)"});
    out.insert(out.end(), infos_.begin(), infos_.end());
    return out;
}

void TrackerCore::time(int slot, Clock::time_point start) {
    ms_[slot] += std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    ran_[slot] = true;
}

void TrackerCore::ensureGray(const ImageView& frame) {
    if (!gray_ready_) gray_ = core::toGray(frame, gray_);
    gray_ready_ = true;
}

void TrackerCore::addFace(const Box& box, float score) {
    if (static_cast<int>(tracks_.size()) >= settings_.max_faces) return;
    const bool known = std::any_of(tracks_.begin(), tracks_.end(), [&](const pipeline::FaceTrack& t) {
        return core::intersectionOverUnion(t.box, box) > kSameFaceIou ||
               core::contains(box, 0.5f * (t.box.x0 + t.box.x1), 0.5f * (t.box.y0 + t.box.y1));
    });
    if (known) return;
    pipeline::FaceTrack& face = tracks_.emplace_back();
    face.id = next_id_++;
    face.locate(box);
    face.result.confidence = score;
    for (const auto& stage : stages_) face.states.push_back(stage->newFaceState());
}

void TrackerCore::detect(const ImageView& frame) {
    const auto start = Clock::now();
    for (const auto& d : detector_->detect(frame)) addFace(d.box, d.score);
    time(kDetect, start);
}

std::optional<Box> TrackerCore::findAgain(const pipeline::FaceTrack& face) {
    // A crop twice the face's size, detected small: ~1 ms instead of a full-frame search.
    const float side = 2.f * std::max(face.box.width(), face.box.height());
    const float cx = 0.5f * (face.box.x0 + face.box.x1), cy = 0.5f * (face.box.y0 + face.box.y1);
    const cv::Rect wanted(cvRound(cx - side / 2), cvRound(cy - side / 2), cvRound(side), cvRound(side));
    const cv::Rect region = wanted & cv::Rect(0, 0, gray_.cols, gray_.rows);
    if (region.area() <= 0) return std::nullopt;
    const double scale = std::min(1.0, static_cast<double>(kVerifyCropWidth) / region.width);
    cv::resize(gray_(region), crop_, cv::Size(), scale, scale, cv::INTER_AREA);
    std::optional<Box> nearest;
    float nearestDistance = std::numeric_limits<float>::max();
    for (const auto& d : detector_->detect(core::viewOf(crop_))) {
        const auto toFrame = [&](float v, int origin) { return static_cast<float>(origin + v / scale); };
        const Box box{toFrame(d.box.x0, region.x), toFrame(d.box.y0, region.y), toFrame(d.box.x1, region.x), toFrame(d.box.y1, region.y)};
        const float distance = std::hypot(0.5f * (box.x0 + box.x1) - cx, 0.5f * (box.y0 + box.y1) - cy);
        if (distance < nearestDistance) {
            nearest = box;
            nearestDistance = distance;
        }
    }
    return nearest;
}

bool TrackerCore::verify(pipeline::FaceTrack& face, Check why) {
    const auto start = Clock::now();
    const std::optional<Box> found = findAgain(face);
    time(kVerify, start);
    if (!found) {
        face.lost = why != Check::InDoubt;
        return false;
    }
    if (why != Check::Unplaced && agrees(face.box, *found, why == Check::InDoubt ? kAgreeAcrossInDoubt : kAgreeAcross)) return false;
    // The detector sees the face elsewhere: the stages start again from its box,
    // unless another followed face is already there.
    const bool taken = std::any_of(tracks_.begin(), tracks_.end(), [&](const pipeline::FaceTrack& t) {
        return &t != &face && core::intersectionOverUnion(t.box, *found) > kSameFaceIou;
    });
    face.lost = taken;
    face.box = *found;
    face.fresh = true;
    return !taken;
}

pipeline::Outcome TrackerCore::sweep(const pipeline::FrameInput& input, pipeline::FaceTrack& face, bool stopAtDoubt) {
    using pipeline::Outcome;
    Outcome worst = Outcome::Ok;
    for (std::size_t k = 0; k < stages_.size(); ++k) {
        if (!infos_[k].available) continue;
        const auto start = Clock::now();
        const Outcome outcome = stages_[k]->run(input, face, face.states[k].get());
        time(kFirstStage + static_cast<int>(k), start);
        worst = pipeline::worse(worst, outcome);
        if (outcome == Outcome::Lost || (stopAtDoubt && outcome != Outcome::Ok)) break;
    }
    return worst;
}

pipeline::Outcome TrackerCore::runStages(const pipeline::FrameInput& input, pipeline::FaceTrack& face) {
    using pipeline::Outcome;
    // A followed face that a stage doubts, or finds far from the previous
    // frame's answer (a fast turn), runs once more from where that stage left
    // it, every stage from the first: after a turn the landmarks then start
    // from the new pose, not the previous frame's (docs/fitting.md, "Tracking").
    const bool followed = !face.fresh;
    Outcome outcome = sweep(input, face, followed);
    if (followed && (outcome == Outcome::Doubtful || outcome == Outcome::Unsettled)) {
        const Outcome again = sweep(input, face, false);
        // The first sweep's doubt stands (the detector still checks the face), unless the face is lost.
        if (again == Outcome::Lost || outcome != Outcome::Doubtful) outcome = again;
    }
    // A face no stage could place is not followed: found again by the next search.
    return face.located ? outcome : Outcome::Lost;
}

void TrackerCore::follow(const pipeline::FrameInput& input, pipeline::FaceTrack& face) {
    using pipeline::Outcome;
    ensureGray(input.colour);
    const bool verifying = settings_.verify_interval > 0;
    Outcome outcome = runStages(input, face);
    // A followed face no stage could place (the fit past its limits after a fast
    // move) is looked for where it was: found, it runs again from the detection and
    // keeps its id and what its stages hold (the identity); else it is lost.
    face.lost = outcome == Outcome::Lost;
    if (face.lost && !face.fresh && verifying && verify(face, Check::Unplaced)) {
        face.located = false;
        outcome = runStages(input, face);
        face.lost = outcome == Outcome::Lost;
    }
    face.doubtful = outcome == Outcome::Doubtful;
    // What is followed must still look like what was followed a frame ago.
    bool seen = !face.lost && appearanceOf(gray_, face.box, appearance_);
    if (seen && !face.fresh && !face.appearance.empty() && alike(appearance_, face.appearance) < kAlike) face.doubtful = true;
    // A face in doubt is checked now; one the detector sees elsewhere runs again
    // from there. Without a detection it stays (blur hides faces from it too).
    if (!face.lost && face.doubtful && !face.fresh && verifying && verify(face, Check::InDoubt)) {
        face.located = false;
        face.lost = runStages(input, face) == Outcome::Lost;
        seen = !face.lost && appearanceOf(gray_, face.box, appearance_);
    }
    // The next frame compares with this one. Copied, not swapped: a track whose buffer has
    // no memory yet would leave appearance_ without any, and the next frame would allocate
    // (256 floats; the copy reuses face.appearance's memory once it has some).
    if (seen) face.appearance.assign(appearance_.begin(), appearance_.end());
    else face.appearance.clear();
}

void TrackerCore::dropLost() {
    tracks_.erase(std::remove_if(tracks_.begin(), tracks_.end(), [](const pipeline::FaceTrack& t) { return t.lost; }), tracks_.end());
}

pipeline::FrameInput TrackerCore::beginFrame(const ImageView& frame, double time_s, FrameResult& out) {
    core::wrap(frame);  // validates the view before anything reads it
    const CameraConfig& c = settings_.camera;
    pipeline::FrameInput input{
        frame, gray_,
        core::cameraFor(frame.width, frame.height, c.horizontal_fov_deg, c.focal_length_px, c.principal_x_px, c.principal_y_px)};
    out.camera = {static_cast<float>(input.camera.fx),
                  static_cast<float>(input.camera.fy),
                  static_cast<float>(input.camera.cx),
                  static_cast<float>(input.camera.cy),
                  frame.width,
                  frame.height};
    // Time must increase; anything else (repeated, backwards, NaN) counts as one frame at 30 fps.
    const bool increasing = std::isfinite(time_s) && (!std::isfinite(last_time_) || time_s > last_time_);
    input.dt = increasing && std::isfinite(last_time_) ? time_s - last_time_ : 1.0 / 30.0;
    if (increasing) last_time_ = time_s;
    ++frame_index_;
    gray_ready_ = false;
    std::fill(ms_.begin(), ms_.end(), 0.0);
    std::fill(ran_.begin(), ran_.end(), false);
    for (auto& t : tracks_) t.located = t.doubtful = false;
    return input;
}

bool TrackerCore::findFaces(const ImageView& frame, const std::vector<Box>* boxes) {
    const int followed = static_cast<int>(tracks_.size());
    if (boxes) {
        for (const Box& box : *boxes) addFace(box, 1.f);
        return true;
    }
    // frame_index_ counts this frame already: the first frame is 0.
    if (followed < settings_.max_faces && (followed == 0 || (frame_index_ - 1) % settings_.detect_interval == 0)) {
        detect(frame);
        return true;
    }
    return false;
}

void TrackerCore::verifyNowAndThen(const ImageView& frame) {
    if (settings_.verify_interval <= 0) return;
    for (auto& t : tracks_) {
        if (t.fresh || t.age % settings_.verify_interval != 0) continue;
        ensureGray(frame);
        verify(t, Check::Periodic);
    }
    dropLost();
}

void TrackerCore::report(FrameResult& out) {
    out.faces.resize(tracks_.size());
    for (std::size_t i = 0; i < tracks_.size(); ++i) {
        pipeline::FaceTrack& t = tracks_[i];
        t.result.id = t.id;
        t.result.tracked = !t.fresh;
        t.result.box = t.box;
        out.faces[i] = t.result;
        t.fresh = false;
        ++t.age;
    }
    std::size_t timings = 0;
    for (std::size_t slot = 0; slot < names_.size(); ++slot) timings += ran_[slot];
    out.timings.resize(timings);
    for (std::size_t slot = 0, j = 0; slot < names_.size(); ++slot) {
        if (!ran_[slot]) continue;
        out.timings[j].stage = names_[slot];
        out.timings[j++].ms = ms_[slot];
    }
}

void TrackerCore::process(const ImageView& frame, double time_s, const std::vector<Box>* boxes, FrameResult& out) {
    const pipeline::FrameInput input = beginFrame(frame, time_s, out);
    const bool searched = findFaces(frame, boxes);  // the caller's boxes, or the detector now and then
    verifyNowAndThen(frame);                        // followed faces, every verify_interval frames
    for (auto& face : tracks_) follow(input, face);
    dropLost();
    if (tracks_.empty() && !searched) {  // every followed face was lost: look again in this very frame
        detect(frame);
        for (auto& face : tracks_) follow(input, face);
        dropLost();
    }
    report(out);
}

void TrackerCore::reset() {
    tracks_.clear();
    last_time_ = std::numeric_limits<double>::quiet_NaN();
}

void TrackerCore::setCalibration(const Calibration& calibration) {
    std::vector<pipeline::StageState*> faces;
    for (std::size_t k = 0; k < stages_.size(); ++k) {
        faces.clear();
        for (auto& t : tracks_)
            if (t.states[k]) faces.push_back(t.states[k].get());
        stages_[k]->setCalibration(calibration, faces);
    }
}

bool TrackerCore::captureNeutral(Calibration& into) const {
    if (tracks_.empty()) return false;
    const pipeline::FaceTrack& first = tracks_.front();
    for (std::size_t k = 0; k < stages_.size(); ++k) {
        if (first.states[k]) stages_[k]->captureNeutral(first.states[k].get(), into);
    }
    return true;
}

const FaceResult* TrackerCore::firstFace() const { return tracks_.empty() ? nullptr : &tracks_.front().result; }

void TrackerCore::resetIdentity() {
    for (auto& t : tracks_) {
        t.result.identity.clear();  // until the next frame reports the mean face
        t.result.identity_calibrated = false;
        for (std::size_t k = 0; k < stages_.size(); ++k) {
            if (t.states[k]) stages_[k]->resetIdentity(t.states[k].get());
        }
    }
}

}  // namespace facetrack::track
