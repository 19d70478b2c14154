#pragma once
// Draws a frame's results over the image: the projected mesh wireframe (face
// region, front-facing triangles), the 68 landmarks, the head's axes and,
// when the gaze stage gives them, the gaze rays.

#include "common/posed_mesh.hpp"
#include "facetrack/face_model.hpp"
#include "facetrack/result.hpp"

#include <opencv2/core.hpp>

#include <array>
#include <vector>

namespace facetrack::tools {

class OverlayRenderer {
public:
    explicit OverlayRenderer(const FaceModel& model);
    void draw(cv::Mat& bgr, const FrameResult& result) const;

private:
    const FaceModel& model_;
    std::vector<std::array<int, 3>> face_triangles_;  // skin region only: the rest (eyes, mouth socket, head) clutters
    int axes_origin_ = 0;
    std::array<EyeRig, 2> eyes_;                             // vertex the pose axes start from (nose bridge)
};

}  // namespace facetrack::tools
