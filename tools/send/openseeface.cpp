#include "send/openseeface.hpp"

#include "send/avatar_pose.hpp"

#include "facetrack/arkit.hpp"
#include "facetrack/error.hpp"

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace facetrack::send {

const std::array<int, 66> kOpenSeeFaceFromIbug = [] {
    std::array<int, 66> map{};
    for (int i = 0; i < 48; ++i) map[static_cast<std::size_t>(i)] = i;
    const int mouth[18] = {49, 50, 51, 52, 53, 55, 56, 57, 58, 59, 48, 61, 62, 63, 54, 65, 66, 67};
    for (int i = 0; i < 18; ++i) map[static_cast<std::size_t>(48 + i)] = mouth[i];
    return map;
}();

namespace {

/// Little-endian writer (x86 and ARM hosts are little-endian; memcpy keeps it exact).
class Writer {
public:
    explicit Writer(std::vector<std::uint8_t>& out) : out_(out) {}
    template <typename T>
    void put(T value) {
        const std::size_t at = out_.size();
        out_.resize(at + sizeof value);
        std::memcpy(out_.data() + at, &value, sizeof value);
    }
    void f(float value) { put(std::isfinite(value) ? value : 0.f); }

private:
    std::vector<std::uint8_t>& out_;
};

float weight(const ExpressionResult* e, const char* name) { return e ? e->arkit[static_cast<std::size_t>(arkitIndex(name))] : 0.f; }

Point2 eyeCentre(const Landmarks68& l, int first) {
    Point2 c;
    for (int i = first; i < first + 6; ++i) c.x += l[static_cast<std::size_t>(i)].x / 6.f, c.y += l[static_cast<std::size_t>(i)].y / 6.f;
    return c;
}

}  // namespace

OpenSeeFaceEncoder::OpenSeeFaceEncoder(std::shared_ptr<const FaceModel> model) : model_(std::move(model)) {
    if (!model_) throw Error("OpenSeeFaceEncoder: no face model");
    const std::vector<int> landmarkVertices = model_->landmarkVertices();
    for (const int i : kOpenSeeFaceFromIbug) sent_vertices_.push_back(landmarkVertices[static_cast<std::size_t>(i)]);
    sent_vertices_.push_back(landmarkVertices[30]);
}

void OpenSeeFaceEncoder::encode(const FrameResult& frame, double time, std::vector<std::uint8_t>& out) {
    out.clear();
    Writer w(out);
    for (const FaceResult& face : frame.faces) {
        if (!face.pose || !face.landmarks) continue;
        const HeadPose& pose = *face.pose;
        const Landmarks68& lm = *face.landmarks;
        const ExpressionResult* expression = face.expression ? &*face.expression : nullptr;
        const std::size_t start = out.size();

        // OpenSeeFace solves PnP with (row, column) image points and a model
        // whose x is the subject's right: its rotation is P R diag(-1, 1, 1),
        // P swapping the camera's x and y (frontal: Euler (180, 0, -90)).
        const Eigen::Quaternionf q(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z);
        Eigen::Matrix3f swap;
        swap << 0, 1, 0, 1, 0, 0, 0, 0, 1;
        const Eigen::Matrix3f r = swap * q.normalized().toRotationMatrix() * Eigen::Vector3f(-1, 1, 1).asDiagonal();
        const Eigen::Quaternionf osf(r);
        cv::Matx33d rq, rr, qq;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) rq(i, j) = r(i, j);
        const cv::Vec3d euler = cv::RQDecomp3x3(rq, rr, qq);

        const float eyePx = std::hypot(lm[45].x - lm[36].x, lm[45].y - lm[36].y);
        const float rightOpen = face.gaze ? face.gaze->right.openness : 1.f - weight(expression, "eyeBlinkRight");
        const float leftOpen = face.gaze ? face.gaze->left.openness : 1.f - weight(expression, "eyeBlinkLeft");

        w.put(time);
        w.put(static_cast<std::int32_t>(face.id));
        w.f(static_cast<float>(frame.camera.width));
        w.f(static_cast<float>(frame.camera.height));
        w.f(rightOpen);
        w.f(leftOpen);
        w.put(static_cast<std::uint8_t>(1));
        w.f(face.fit_residual ? *face.fit_residual * eyePx : 0.f);
        for (const float v : {osf.x(), osf.y(), osf.z(), osf.w()}) w.f(v);
        for (int i = 0; i < 3; ++i) w.f(static_cast<float>(euler[i]));
        w.f(pose.translation_mm.y / kOpenSeeFaceUnitMm);
        w.f(pose.translation_mm.x / kOpenSeeFaceUnitMm);
        w.f(pose.translation_mm.z / kOpenSeeFaceUnitMm);

        // Confidences: the face's for the 66 points; the pupils' is the eye's openness (0 without gaze).
        for (int i = 0; i < 66; ++i) w.f(face.confidence);
        w.f(face.gaze ? face.gaze->right.openness : 0.f);
        w.f(face.gaze ? face.gaze->left.openness : 0.f);
        for (const int i : kOpenSeeFaceFromIbug) w.f(lm[static_cast<std::size_t>(i)].x), w.f(lm[static_cast<std::size_t>(i)].y);
        // 66, 67: the right and left pupils (the eye centres without gaze).
        const Point2 rightPupil = face.gaze ? face.gaze->right.pupil_px : eyeCentre(lm, 36);
        const Point2 leftPupil = face.gaze ? face.gaze->left.pupil_px : eyeCentre(lm, 42);
        for (const Point2 p : {rightPupil, leftPupil}) w.f(p.x), w.f(p.y);

        // 3D points in the head frame, OpenSeeFace's axes and units, the nose
        // tip at x = y = 0, written as (x, -y, -z) as facetracker.py does.
        model_->vertices(face.identity, expression ? expression->native : std::vector<float>{}, sent_vertices_, sent_points_);
        const Vec3 nose = sent_points_.back();
        const auto put3 = [&](const Vec3& p) {
            w.f(-(p.x - nose.x) / kOpenSeeFaceUnitMm);
            w.f(-(p.y - nose.y) / kOpenSeeFaceUnitMm);
            w.f(-p.z / kOpenSeeFaceUnitMm);
        };
        for (std::size_t k = 0; k < kOpenSeeFaceFromIbug.size(); ++k) put3(sent_points_[k]);
        const EyeballGeometry right = model_->rightEyeball(), left = model_->leftEyeball();
        // The pupil on the eyeball's surface, along the gaze (head frame) or the rest axis.
        const auto pupil = [](const EyeballGeometry& e, const EyeGaze* g) {
            const Vec3 d = g ? g->direction_head : e.optical_axis;
            return Vec3{e.centre.x + e.radius_mm * d.x, e.centre.y + e.radius_mm * d.y, e.centre.z + e.radius_mm * d.z};
        };
        put3(pupil(right, face.gaze ? &face.gaze->right : nullptr));
        put3(pupil(left, face.gaze ? &face.gaze->left : nullptr));
        put3(right.centre);
        put3(left.centre);

        // The 14 features, from the ARKit weights (OpenSeeFace measures them
        // on its 2D points with self-calibrating ranges: docs/protocols.md).
        const auto both = [&](const char* l, const char* r) { return 0.5f * (weight(expression, l) + weight(expression, r)); };
        const float open = weight(expression, "jawOpen");
        w.f(-weight(expression, "eyeBlinkLeft"));
        w.f(-weight(expression, "eyeBlinkRight"));
        struct Side {
            const char *browDown, *browOuterUp, *smile, *frown, *stretch;
        };
        static constexpr Side kSides[2] = {
            {"browDownLeft", "browOuterUpLeft", "mouthSmileLeft", "mouthFrownLeft", "mouthStretchLeft"},
            {"browDownRight", "browOuterUpRight", "mouthSmileRight", "mouthFrownRight", "mouthStretchRight"}};
        const float innerUp = weight(expression, "browInnerUp");
        for (const Side& side : kSides) {
            const float down = weight(expression, side.browDown), outerUp = weight(expression, side.browOuterUp);
            w.f(down - innerUp);                     // steepness
            w.f(0.5f * (innerUp + outerUp) - down);  // up-down
            w.f(std::fabs(outerUp - innerUp));       // quirk
        }
        for (const Side& side : kSides) {
            w.f(weight(expression, side.smile) - weight(expression, side.frown));       // corner up-down
            w.f(weight(expression, side.stretch) - weight(expression, "mouthPucker"));  // corner in-out
        }
        w.f(open);
        w.f(both("mouthStretchLeft", "mouthStretchRight") - weight(expression, "mouthPucker"));
        if (out.size() - start != kOpenSeeFaceFaceBytes) throw Error("OpenSeeFace packet has the wrong size (a bug)");
    }
}

}  // namespace facetrack::send
