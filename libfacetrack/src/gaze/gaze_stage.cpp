#include "gaze/gaze_stage.hpp"

#include "core/one_euro.hpp"
#include "gaze/eye_model_data.hpp"
#include "gaze/eye_patch.hpp"
#include "gaze/gaze_fit.hpp"
#include "gaze/iris_net.hpp"
#include "model/internals.hpp"

#include "facetrack/posed_mesh.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <optional>

namespace facetrack::gaze {

float blinkWeight(float openness) { return std::clamp((0.8f - openness) / 0.55f, 0.f, 1.f); }
float wideWeight(float ratio) { return std::clamp((ratio - 1.1f) / 0.3f, 0.f, 1.f); }

namespace {

constexpr float kDeg = 3.14159265358979f / 180.f;
constexpr int kRegionW = kClassifiedRegion.columns();
constexpr int kRegionH = kClassifiedRegion.rows();
/// The open-eye reference: a running 70th percentile of the aperture, moved by
/// kReferenceStep a frame; on a new face's n-th frame by kReferenceStep *
/// max(1, kReferenceWarmup / n) (a stochastic-approximation schedule), so it
/// reaches this face's own opening in about a second instead of several: with
/// the fixed step, a face whose eyes open wider than the model's read as
/// eyeWide 0.6 at first, falling over 40 frames.
constexpr float kReferenceQuantile = 0.7f;
constexpr float kReferenceStep = 0.002f;
constexpr float kReferenceWarmup = 20.f;
/// An eye is data for the gaze fit from this openness (the forest's reading)
/// on, fully 0.25 above it. A closing lid covers the iris from above and would
/// drag the gaze down; too high a bar, and an eye looking down, its lids
/// lowered, gives no data, so the gaze holds its pitch and the eye reads as
/// closing (docs/gaze.md: 0.6 read a look-down after looking ahead as eyeBlink
/// 0.70; 0.45 reads it as 0.47 and moves the gaze 0.00 deg across a blink).
constexpr float kDataFromOpenness = 0.45f;

struct EyeState {
    EyePatch patch;
    // Not brace-initialised: cv::Mat{a, b, c} is an initializer-list matrix of three values.
    cv::Mat iris = cv::Mat(kRegionH, kRegionW, CV_32F), open = cv::Mat(kRegionH, kRegionW, CV_32F);
    float reference = 0.f;  // the face's open-eye aperture
    int samples = 0;        // apertures the reference has seen
};

/// The output's 1-euro filter, on yaw and pitch in degrees: a fixation is held
/// still (cutoff 0.8 Hz), a saccade of hundreds of degrees a second passes in
/// about a frame (beta 0.05 per deg/s; the speed itself low-passed at 5 Hz so it rises at once).
const core::OneEuroSettings kGazeSmoothing{0.8, 0.05, 5.0};
/// The eyeball centres' 1-euro filter, camera frame in mm. They come from the
/// fit's head pose, whose frame-to-frame jitter moves them by tenths of a
/// millimetre, and 0.6 mm reads as a 3-degree turn of the eye: a still head's
/// eyeballs are held still (cutoff 1 Hz), a turning head's followed (beta 1
/// per mm/s: at 60 deg/s they move ~100 mm/s; beta 0.05 lagged them by a
/// frame, a 13-degree gaze error).
const core::OneEuroSettings kEyeballSmoothing{1.0, 1.0, 1.0};

struct GazeFaceState final : pipeline::StageState {
    std::array<EyeState, 2> eyes;                                         // the subject's left, right
    GazeAngles angles{Eigen::Vector2f::Zero(), Eigen::Vector2f::Zero()};  // the MAP estimate
    bool have_angles = false;
    core::OneEuroFilter smoothing{kGazeSmoothing};
    Eigen::VectorXd sample = Eigen::VectorXd::Zero(4), output = Eigen::VectorXd::Zero(4);
    core::OneEuroFilter eyeball_smoothing{kEyeballSmoothing};
    Eigen::VectorXd eyeball_sample = Eigen::VectorXd::Zero(6);
    std::vector<float> centres_identity;  // the identity the eyeball centres were computed for
    bool have_centres = false;
    std::array<Vec3, 2> centres;                 // eyeball rotation centres on the identity's mesh (model frame)
    std::array<std::array<Vec3, 2>, 2> corners;  // that mesh's outer and inner eye corners (FaceModel::landmarkPoints)
    std::array<Eigen::Vector3f, 2> offset{Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero()};  // landmark correction, model frame
    bool have_offset = false;
    std::vector<Vec3> mesh;
    EyePatch recut;  // the corner cascade's later stages' patches
    cv::Mat padded;  // an eye patch padded for the pixel forest
};

/// Indices of the face model's eye shapes (-1 when it has no such shape).
struct EyeShapes {
    int blink, lookUp, lookDown, lookIn, lookOut, wide;
};

std::array<EyeShapes, 2> eyeShapes(const FaceModel& face) {
    const auto& names = face.expressionNames();
    const auto index = [&](const std::string& n) {
        const auto it = std::find(names.begin(), names.end(), n);
        return it == names.end() ? -1 : static_cast<int>(it - names.begin());
    };
    std::array<EyeShapes, 2> shapes;
    for (int e = 0; e < 2; ++e) {
        const std::string s = e == 0 ? "_L" : "_R";
        shapes[e] = {index("eyeBlink" + s),  index("eyeLookUp" + s),  index("eyeLookDown" + s),
                     index("eyeLookIn" + s), index("eyeLookOut" + s), index("eyeWide" + s)};
    }
    return shapes;
}

std::vector<int> gazeExpressions(const FaceModel& face) {
    std::vector<int> out;
    for (const EyeShapes& s : eyeShapes(face)) {
        for (const int i : {s.blink, s.lookUp, s.lookDown, s.lookIn, s.lookOut, s.wide})
            if (i >= 0) out.push_back(i);
    }
    return out;
}

/// An eye's aperture against what an open eye shows at a gaze pitch: the
/// openness ratio (1 as open as the face's reference, 0 closed) and the eye's
/// weight as data for the gaze fit.
struct EyeReading {
    float ratio = 0.f;
    float weight = 0.f;
};

EyeReading readEye(const EyeModelData& model, const LidsFollowingGaze& lids, float forestAperture, float aperture, float reference,
                   float pitchRad) {
    // Looking down lowers the lids: the open eye's expected aperture follows the gaze pitch.
    const float closed = model.closed_aperture;
    const float expected = std::max(closed + (reference - closed) * lids.share(std::min(0.f, pitchRad) / kDeg), closed + 1e-3f);
    EyeReading r;
    r.ratio = (aperture - closed) / (expected - closed);
    // Data only from an open eye (kDataFromOpenness), judged by the forest's reading alone
    // (with the average, 300-W's pupil p95 rose from 0.048 to 0.051).
    const float forestOpenness = (forestAperture - closed) / (expected - closed);
    r.weight = std::clamp((forestOpenness - kDataFromOpenness) / 0.25f, 0.f, 1.f);
    return r;
}

class GazeStage final : public pipeline::Stage {
public:
    GazeStage(std::shared_ptr<const EyeModel> eyes, std::shared_ptr<const FaceModel> face)
        : eyes_(std::move(eyes)), face_(std::move(face)), rigs_(EyeRig::both(*face_)), shapes_(eyeShapes(*face_)), lids_(*face_) {
        if (!model::dataOf(*eyes_).iris_net.empty())
            iris_net_.emplace(model::dataOf(*eyes_).iris_net, "eye model '" + eyes_->sourcePath() + "': its iris net");
    }

    StageInfo info() const override {
        return {"gaze", true,
                std::string("eye patches, ") + (iris_net_ ? std::string("iris CNN on the ") + iris_net_->engineName() : "pixel forest") +
                    ", aperture forest, binocular MAP fit (" + eyes_->sourcePath() + ")"};
    }

    std::unique_ptr<pipeline::StageState> newFaceState() const override {
        auto s = std::make_unique<GazeFaceState>();
        for (auto& e : s->eyes) e.reference = model::dataOf(*eyes_).open_aperture;
        return s;
    }

    pipeline::Contract contract() const override {
        using pipeline::Field;
        return {Field::Landmarks | Field::Pose | Field::Identity, Field::Gaze | Field::Expression, gazeExpressions(*face_), true};
    }

    void resetIdentity(pipeline::StageState* state) const override {
        auto& s = static_cast<GazeFaceState&>(*state);
        for (auto& e : s.eyes) {
            e.reference = model::dataOf(*eyes_).open_aperture;
            e.samples = 0;
        }
        s.have_centres = false;
        s.have_offset = false;
        s.smoothing.reset();
        s.eyeball_smoothing.reset();
    }

    pipeline::Outcome run(const pipeline::FrameInput& frame, pipeline::FaceTrack& face, pipeline::StageState* state) override {
        FaceResult& r = face.result;
        auto& s = static_cast<GazeFaceState&>(*state);
        if (!r.landmarks || !r.pose) {
            r.gaze.reset();
            return pipeline::Outcome::Ok;
        }
        updateCentres(r, s);
        const HeadPose& pose = *r.pose;
        const Eigen::Quaternionf q(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z);
        const Eigen::Matrix3f R = q.normalized().toRotationMatrix();
        const Eigen::Vector3f t(pose.translation_mm.x, pose.translation_mm.y, pose.translation_mm.z);

        const EyeModelData& model = model::dataOf(*eyes_);
        std::array<EyeObservation, 2> seen;
        std::array<float, 2> ratio{}, openness{};
        std::array<bool, 2> cut{};
        std::array<std::array<Point2, 2>, 2> corners;  // per eye: outer, inner
        for (int e = 0; e < 2; ++e) {
            const Eye eye = e == 0 ? Eye::Left : Eye::Right;
            EyePatch& patch = s.eyes[static_cast<std::size_t>(e)].patch;
            cut[e] = cutEyePatch(frame.gray, *r.landmarks, eye, patch);
            corners[e] = cut[e] ? eyeCorners(model, frame.gray, patch, s.recut)
                                : std::array<Point2, 2>{(*r.landmarks)[static_cast<std::size_t>(outerCorner(eye))],
                                                        (*r.landmarks)[static_cast<std::size_t>(innerCorner(eye))]};
        }
        placeEyeballs(corners, R, t, frame.camera, s);
        classify(model, cut, s);
        for (int e = 0; e < 2; ++e) {
            const Eigen::Vector3f c = Eigen::Vector3f(s.centres[e].x, s.centres[e].y, s.centres[e].z) + s.offset[e];
            s.eyeball_sample.segment<3>(3 * e) = (R * c + t).cast<double>();
        }
        const Eigen::VectorXd& eyeballs = s.eyeball_smoothing(s.eyeball_sample, frame.dt);
        std::array<float, 2> forestAperture{}, aperture{};
        for (int e = 0; e < 2; ++e) {
            EyeState& eye = s.eyes[static_cast<std::size_t>(e)];
            seen[e].centre = eyeballs.segment<3>(3 * e).cast<float>();
            if (!cut[e]) continue;
            model.aperture.evaluate(eye.patch.pixels, 0, 0, &forestAperture[e]);
            // Two readings of one gap, averaged: the forest's alone read an eye looking down, its
            // lids lowered, as half closed frame by frame (docs/gaze.md).
            aperture[e] = 0.5f * (forestAperture[e] + openMapAperture(model, eye.open));
            seen[e].patch = &eye.patch;
            seen[e].iris = &eye.iris;
            seen[e].open = &eye.open;
            const EyeReading reading = readEye(model, lids_, forestAperture[e], aperture[e], eye.reference,
                                               s.angles[static_cast<std::size_t>(e)].y());
            ratio[e] = reading.ratio;
            seen[e].weight = reading.weight;
        }
        probeLookingDown(model, cut, forestAperture, aperture, R, frame.camera, s, seen, ratio);
        for (int e = 0; e < 2; ++e) {
            if (!cut[e]) continue;
            EyeState& eye = s.eyes[static_cast<std::size_t>(e)];
            openness[e] = std::clamp(ratio[e], 0.f, 1.f);
            // The reference tracks this face's open-eye aperture (a quantile, robust to blinks).
            const float step = kReferenceStep * std::max(1.f, kReferenceWarmup / static_cast<float>(++eye.samples));
            eye.reference += step * (aperture[e] > eye.reference ? kReferenceQuantile : kReferenceQuantile - 1.f);
            eye.reference = std::clamp(eye.reference, model.closed_aperture + 0.6f * (model.open_aperture - model.closed_aperture),
                                       model.closed_aperture + 1.6f * (model.open_aperture - model.closed_aperture));
        }
        const core::Camera& camera = frame.camera;
        // Both eyes closed: the output holds exactly (the filter is not fed, so it does not catch up meanwhile).
        const bool seeing = seen[0].weight > 0.f || seen[1].weight > 0.f || !s.have_angles;
        s.angles = fitGaze(seen, R, camera, s.angles, s.have_angles);
        s.have_angles = true;
        if (seeing) {
            for (int k = 0; k < 4; ++k) s.sample[k] = s.angles[static_cast<std::size_t>(k / 2)][k % 2] / kDeg;
            s.output = s.smoothing(s.sample, frame.dt);
        }
        const Eigen::VectorXd& smooth = s.output;

        GazeResult gaze;
        for (int e = 0; e < 2; ++e) {
            EyeGaze& out = e == 0 ? gaze.left : gaze.right;
            const Eigen::Vector2f a(static_cast<float>(smooth[2 * e] * kDeg), static_cast<float>(smooth[2 * e + 1] * kDeg));
            const Eigen::Vector3f head = gazeDirection(a.x(), a.y());
            const Eigen::Vector3f cam = R * head;
            out.direction = {cam.x(), cam.y(), cam.z()};
            out.direction_head = {head.x(), head.y(), head.z()};
            out.yaw_deg = a.x() / kDeg;
            out.pitch_deg = a.y() / kDeg;
            out.openness = openness[e];
            const Eigen::Vector2f pupil = irisCentreInImage(seen[e].centre, R, camera, a);
            out.pupil_px = {pupil.x(), pupil.y()};
        }
        r.gaze = gaze;
        writeEyeShapes(r, gaze, ratio);
        return pipeline::Outcome::Ok;
    }

private:
    /// An eye whose lids are lower than the held gaze pitch expects is closing
    /// or looking down. Read at the held pitch alone it gives the fit too little
    /// data to tell (a look-down after looking ahead read as a blink, docs/gaze.md);
    /// so where an eye is partly covered, a probe fit with every visible eye as
    /// full data asks where the irises are, and when at the probe's pitch the eye
    /// would not read as a blink (eyeBlink < 0.5), its lids were following its
    /// gaze: its openness is read at that pitch (its data weight too, where that
    /// is higher). A closing lid over a still iris does not pass: the iris stays
    /// up, so at its pitch the lids still read low.
    void probeLookingDown(const EyeModelData& model, const std::array<bool, 2>& cut, const std::array<float, 2>& forestAperture,
                          const std::array<float, 2>& aperture, const Eigen::Matrix3f& R, const core::Camera& camera,
                          const GazeFaceState& s, std::array<EyeObservation, 2>& seen, std::array<float, 2>& ratio) const {
        bool partlyCovered = false;
        std::array<EyeObservation, 2> probe = seen;
        for (std::size_t e = 0; e < 2; ++e) {
            partlyCovered = partlyCovered || (cut[e] && seen[e].weight < 1.f);
            probe[e].weight = cut[e] && forestAperture[e] > model.closed_aperture ? 1.f : 0.f;
        }
        if (!partlyCovered) return;
        const GazeAngles looked = fitGaze(probe, R, camera, s.angles, s.have_angles);
        for (std::size_t e = 0; e < 2; ++e) {
            if (!cut[e] || seen[e].weight >= 1.f) continue;
            const EyeReading reading = readEye(model, lids_, forestAperture[e], aperture[e], s.eyes[e].reference, looked[e].y());
            if (blinkWeight(reading.ratio) < 0.5f && reading.ratio > ratio[e]) {
                ratio[e] = reading.ratio;
                seen[e].weight = std::max(seen[e].weight, reading.weight);
            }
        }
    }

    /// The iris and open maps of the eyes that were cut: by the iris CNN when the model has one, else the pixel forest.
    void classify(const EyeModelData& model, const std::array<bool, 2>& cut, GazeFaceState& s) {
        if (iris_net_) {
            std::array<const cv::Mat*, 2> patches{};
            std::array<cv::Mat*, 2> iris{}, open{};
            for (std::size_t e = 0; e < 2; ++e) {
                patches[e] = cut[e] ? &s.eyes[e].patch.pixels : nullptr;
                iris[e] = &s.eyes[e].iris;
                open[e] = &s.eyes[e].open;
            }
            classifyByNet(model, *iris_net_, patches, iris, open);
            return;
        }
        for (std::size_t e = 0; e < 2; ++e)
            if (cut[e]) classifyByForest(model, s.eyes[e].patch.pixels, s.padded, s.eyes[e].iris, s.eyes[e].open);
    }

    /// The eyeball centres of this face's identity (once per identity: a mesh evaluation).
    void updateCentres(const FaceResult& r, GazeFaceState& s) const {
        if (s.have_centres && s.centres_identity == r.identity) return;
        face_->vertices(r.identity, {}, s.mesh);
        // The corners in the landmarks' convention: the observed corners (the cascade's, the
        // landmarks') are 300-W-style, about 1 mm above the model's corner vertices.
        const std::vector<Vec3> points = face_->landmarkPoints(s.mesh);
        for (int e = 0; e < 2; ++e) {
            const Eigen::Vector3f c = rotationCentre(e == 0 ? face_->leftEyeball() : face_->rightEyeball(), rigs_[e].centre(s.mesh));
            s.centres[e] = {c.x(), c.y(), c.z()};
            const Eye eye = e == 0 ? Eye::Left : Eye::Right;
            s.corners[e] = {points[static_cast<std::size_t>(outerCorner(eye))], points[static_cast<std::size_t>(innerCorner(eye))]};
        }
        s.centres_identity = r.identity;
        s.have_centres = true;
    }

    /// Ties each eyeball to the eye corners seen in the image (`corners`: per
    /// eye, outer and inner), not only to the fitted mesh: the fit places the
    /// mesh as a compromise over all 68 landmarks, which can leave its eyes a
    /// few mm off the image's eyes. The observed corners, back-projected at the
    /// mesh corners' depths, give where the eye is; the difference to the
    /// mesh's corners (model frame) is averaged over frames (a per-user
    /// refinement that does not follow landmark jitter).
    void placeEyeballs(const std::array<std::array<Point2, 2>, 2>& corners, const Eigen::Matrix3f& R, const Eigen::Vector3f& t,
                       const core::Camera& camera, GazeFaceState& s) const {
        for (int e = 0; e < 2; ++e) {
            Eigen::Vector3f delta = Eigen::Vector3f::Zero();
            for (int k = 0; k < 2; ++k) {
                const Vec3& v = s.corners[e][static_cast<std::size_t>(k)];
                const Eigen::Vector3f mesh = R * Eigen::Vector3f(v.x, v.y, v.z) + t;
                const Point2 p = corners[static_cast<std::size_t>(e)][static_cast<std::size_t>(k)];
                const Eigen::Vector3f seen(static_cast<float>((p.x - camera.cx) / camera.fx) * mesh.z(),
                                           static_cast<float>((p.y - camera.cy) / camera.fy) * mesh.z(), mesh.z());
                delta += 0.5f * R.transpose() * (seen - mesh);
            }
            if (!delta.allFinite() || delta.norm() > 15.f) continue;  // a landmark far off: keep the last correction
            s.offset[e] = s.have_offset ? Eigen::Vector3f(0.9f * s.offset[e] + 0.1f * delta) : delta;
        }
        s.have_offset = true;
    }

    void writeEyeShapes(FaceResult& r, const GazeResult& gaze, const std::array<float, 2>& ratio) const {
        if (!r.expression) return;
        std::vector<float>& native = r.expression->native;
        const auto set = [&](int index, float value) {
            if (index >= 0 && static_cast<std::size_t>(index) < native.size()) native[static_cast<std::size_t>(index)] = value;
        };
        for (int e = 0; e < 2; ++e) {
            const EyeGaze& g = e == 0 ? gaze.left : gaze.right;
            const EyeShapes& k = shapes_[e];
            set(k.blink, blinkWeight(g.openness));
            set(k.wide, wideWeight(ratio[e]));
            // Yaw > 0 looks to the subject's left: outwards for the left eye, inwards for the right.
            const float outwards = e == 0 ? g.yaw_deg : -g.yaw_deg;
            set(k.lookOut, std::clamp(outwards / kLookSidewaysFullDeg, 0.f, 1.f));
            set(k.lookIn, std::clamp(-outwards / kLookSidewaysFullDeg, 0.f, 1.f));
            set(k.lookUp, std::clamp(g.pitch_deg / kLookUpFullDeg, 0.f, 1.f));
            set(k.lookDown, std::clamp(-g.pitch_deg / kLookDownFullDeg, 0.f, 1.f));
        }
        r.expression->arkit = face_->toArkit(native);
    }

    std::shared_ptr<const EyeModel> eyes_;
    std::shared_ptr<const FaceModel> face_;
    std::array<EyeRig, 2> rigs_;
    std::array<EyeShapes, 2> shapes_;
    LidsFollowingGaze lids_;
    std::optional<IrisNet> iris_net_;
};

}  // namespace

LidsFollowingGaze::LidsFollowingGaze(const FaceModel& face) {
    const std::array<EyeShapes, 2> shapes = eyeShapes(face);
    const std::array<int, 2> down = {shapes[0].lookDown, shapes[1].lookDown};
    if (down[0] < 0 || down[1] < 0) {
        for (int k = 0; k < kSamples; ++k)
            share_[static_cast<std::size_t>(k)] = std::max(0.55f, 1.f - 0.012f * 5.f * static_cast<float>(k));
        return;
    }
    // Per eye (68-point numbering): corners, then upper and lower lid points facing each other.
    struct Lids {
        int outer, inner, upper1, upper2, lower1, lower2;
    };
    constexpr std::array<Lids, 2> kLids = {{{45, 42, 44, 43, 46, 47}, {36, 39, 37, 38, 41, 40}}};
    const auto gap = [&](float weight) {
        std::vector<float> w(face.expressionNames().size(), 0.f);
        w[static_cast<std::size_t>(down[0])] = w[static_cast<std::size_t>(down[1])] = weight;
        const std::vector<Vec3> p = face.landmarkPoints(face.vertices({}, w));
        const auto at = [&](int i) { return p[static_cast<std::size_t>(i)]; };
        float sum = 0.f;
        for (const Lids& l : kLids) {
            const float width = std::hypot(at(l.inner).x - at(l.outer).x, at(l.inner).y - at(l.outer).y);
            sum += 0.5f * (std::fabs(at(l.upper1).y - at(l.lower1).y) + std::fabs(at(l.upper2).y - at(l.lower2).y)) / width;
        }
        return sum;
    };
    const float ahead = gap(0.f);
    for (int k = 0; k < kSamples; ++k) {
        const float weight = 5.f * static_cast<float>(k) / kLookDownFullDeg;
        share_[static_cast<std::size_t>(k)] = ahead > 0.f ? std::clamp(gap(weight) / ahead, 0.05f, 1.f) : 1.f;
    }
}

float LidsFollowingGaze::share(float pitchDeg) const {
    const float x = std::clamp(-pitchDeg / 5.f, 0.f, static_cast<float>(kSamples - 1));
    const int k = std::min(static_cast<int>(x), kSamples - 2);
    const float t = x - static_cast<float>(k);
    return (1.f - t) * share_[static_cast<std::size_t>(k)] + t * share_[static_cast<std::size_t>(k + 1)];
}

std::unique_ptr<pipeline::Stage> makeGazeStage(std::shared_ptr<const EyeModel> eyes, std::shared_ptr<const FaceModel> face) {
    if (!eyes) {
        return pipeline::notAvailable("gaze",
                                      "no eye model given (Models::loadDefault() reads " + EyeModel::defaultPath() + " when it exists)");
    }
    return std::make_unique<GazeStage>(std::move(eyes), std::move(face));
}

}  // namespace facetrack::gaze
