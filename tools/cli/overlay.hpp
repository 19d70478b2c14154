#pragma once
// Draws a frame's results over the image: the projected mesh wireframe (face
// region, front-facing triangles), the 68 landmarks and the head's axes.

#include "facetrack/face_model.hpp"
#include "facetrack/result.hpp"

#include <opencv2/core.hpp>

#include <array>
#include <vector>

namespace facetrack::cli {

class OverlayRenderer {
public:
    explicit OverlayRenderer(const FaceModel& model);
    void draw(cv::Mat& bgr, const FrameResult& result) const;

private:
    const FaceModel& model_;
    std::vector<std::array<int, 3>> face_triangles_;  // skin region only: the rest (eyes, mouth socket, head) clutters
    int axes_origin_ = 0;                             // vertex the pose axes start from (nose bridge)
};

}  // namespace facetrack::cli
