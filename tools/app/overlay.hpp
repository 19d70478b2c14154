#pragma once
// Draws a frame's results over the image: the projected mesh wireframe (face
// region, front-facing triangles), the 68 landmarks, the head's axes and,
// when the gaze stage gives them, the gaze rays.

#include "facetrack/face_model.hpp"
#include "facetrack/posed_mesh.hpp"
#include "facetrack/result.hpp"

#include <opencv2/core.hpp>

#include <array>
#include <memory>
#include <vector>

namespace facetrack::tools {

class OverlayRenderer {
public:
    explicit OverlayRenderer(std::shared_ptr<const FaceModel> model);
    /// Not thread-safe: reuses its mesh buffers from call to call. A caller
    /// that has posed the first face's mesh already (MeshPoser::modelFrame)
    /// passes it as `firstFaceMesh`, so that it is not posed twice.
    void draw(cv::Mat& bgr, const FrameResult& result, const std::vector<Vec3>* firstFaceMesh = nullptr);

private:
    MeshPoser poser_;
    std::vector<std::array<int, 3>> face_triangles_;  // skin region only: the rest (eyes, mouth socket, head) clutters
    int axes_origin_ = 0;                             // vertex the pose axes start from (nose bridge)
    std::vector<Vec3> mesh_;                          // model frame, reused
    std::vector<cv::Point3f> camera_;                 // camera frame, reused
    cv::Mat layer_;
};

}  // namespace facetrack::tools
