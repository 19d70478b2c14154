#include "overlay.hpp"

#include <opencv2/imgproc.hpp>

namespace facetrack::tools {

namespace {

struct Projector {
    CameraIntrinsics camera;
    HeadPose pose;
    /// Camera-frame position (mm) of a model-frame point (mm).
    cv::Point3f toCamera(const Vec3& v) const {
        const Vec3 c = facetrack::toCamera(pose, v);
        return {c.x, c.y, c.z};
    }
    cv::Point2f project(const cv::Point3f& p) const { return {camera.fx * p.x / p.z + camera.cx, camera.fy * p.y / p.z + camera.cy}; }
};

constexpr int kShift = 4;  // sub-pixel drawing: coordinates times 16
cv::Point fixedPoint(const cv::Point2f& p) { return {cvRound(p.x * (1 << kShift)), cvRound(p.y * (1 << kShift))}; }

}  // namespace

OverlayRenderer::OverlayRenderer(std::shared_ptr<const FaceModel> model) : poser_(std::move(model)) {
    const FaceModel& m = poser_.model();
    const int face = m.faceVertexCount();
    for (const auto& t : m.triangles()) {
        if (t[0] < face && t[1] < face && t[2] < face) face_triangles_.push_back(t);
    }
    axes_origin_ = m.landmarkVertices()[27];
}

void OverlayRenderer::draw(cv::Mat& bgr, const FrameResult& result, const std::vector<Vec3>* firstFaceMesh) {
    for (std::size_t f = 0; f < result.faces.size(); ++f) {
        const FaceResult& face = result.faces[f];
        if (face.pose && face.expression) {
            const Projector projector{result.camera, *face.pose};
            if (f > 0 || !firstFaceMesh) poser_.modelFrame(face, mesh_);
            const std::vector<Vec3>& vertices = f == 0 && firstFaceMesh ? *firstFaceMesh : mesh_;
            std::vector<cv::Point3f>& cam = camera_;
            cam.resize(vertices.size());
            for (std::size_t i = 0; i < vertices.size(); ++i) cam[i] = projector.toCamera(vertices[i]);
            // Drawn on a copy and blended at 35 %: the face stays visible under the wires.
            bgr.copyTo(layer_);
            cv::Mat& layer = layer_;
            const cv::Scalar mesh(170, 200, 120);
            for (const auto& t : face_triangles_) {
                const cv::Point3f &a = cam[t[0]], &b = cam[t[1]], &c = cam[t[2]];
                if (a.z <= 0 || b.z <= 0 || c.z <= 0) continue;
                if ((b - a).cross(c - a).dot(a) >= 0) continue;  // faces away from the camera
                const cv::Point pa = fixedPoint(projector.project(a)), pb = fixedPoint(projector.project(b)),
                                pc = fixedPoint(projector.project(c));
                cv::line(layer, pa, pb, mesh, 1, cv::LINE_8, kShift);
                cv::line(layer, pb, pc, mesh, 1, cv::LINE_8, kShift);
            }
            cv::addWeighted(layer, 0.35, bgr, 0.65, 0.0, bgr);
            // Model axes, 50 mm long: x red (subject's left), y green (up), z blue (out of the face).
            const Vec3 o = vertices[axes_origin_];
            const cv::Point2f origin = projector.project(projector.toCamera(o));
            const std::array<std::pair<Vec3, cv::Scalar>, 3> axes = {
                {{{o.x + 50, o.y, o.z}, {0, 0, 255}}, {{o.x, o.y + 50, o.z}, {0, 200, 0}}, {{o.x, o.y, o.z + 50}, {255, 80, 0}}}};
            for (const auto& [tip, colour] : axes) {
                cv::line(bgr, fixedPoint(origin), fixedPoint(projector.project(projector.toCamera(tip))), colour, 2, cv::LINE_AA, kShift);
            }
            if (face.gaze) {
                // Gaze rays, 60 mm from each eyeball's centre (camera frame directions).
                const std::array<const EyeGaze*, 2> gaze = {&face.gaze->left, &face.gaze->right};
                const std::array<Vec3, 2> centres = poser_.eyeCentres(vertices);
                for (int e = 0; e < 2; ++e) {
                    const cv::Point3f from = projector.toCamera(centres[e]);
                    const Vec3& d = gaze[e]->direction;
                    const cv::Point3f to = from + 60.f * cv::Point3f(d.x, d.y, d.z);
                    if (from.z <= 0 || to.z <= 0) continue;
                    cv::line(bgr, fixedPoint(projector.project(from)), fixedPoint(projector.project(to)), cv::Scalar(255, 255, 0), 2,
                             cv::LINE_AA, kShift);
                }
                // Pupils: a ring, filled while the eye is open.
                for (const EyeGaze* g : gaze) {
                    const int thickness = g->openness > 0.5f ? -1 : 1;
                    cv::circle(bgr, fixedPoint({g->pupil_px.x, g->pupil_px.y}), 3 << kShift, cv::Scalar(255, 0, 255), thickness,
                               cv::LINE_AA, kShift);
                }
            }
        }
        if (face.landmarks) {
            for (const auto& p : *face.landmarks) {
                cv::circle(bgr, fixedPoint({p.x, p.y}), 2 << kShift, cv::Scalar(0, 255, 255), -1, cv::LINE_AA, kShift);
            }
        }
        cv::rectangle(bgr, cv::Point(cvRound(face.box.x0), cvRound(face.box.y0)), cv::Point(cvRound(face.box.x1), cvRound(face.box.y1)),
                      face.tracked ? cv::Scalar(0, 200, 0) : cv::Scalar(0, 140, 255), 1);
    }
}

}  // namespace facetrack::tools
