#pragma once
// OpenSeeFace's binary UDP packet (facetracker.py; VSeeFace, VTube Studio's
// and others' OpenSeeFace receivers, default port 11573). docs/protocols.md
// has the layout and where facetrack's values differ from OpenSeeFace's own.

#include "facetrack/face_model.hpp"
#include "facetrack/result.hpp"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace facetrack::send {

constexpr std::size_t kOpenSeeFaceFaceBytes = 1785;
constexpr int kOpenSeeFacePort = 11573;
/// OpenSeeFace's 3D model is in units of about 142 mm: its outer eye corners
/// are 0.632 units apart, an adult's about 90 mm.
constexpr float kOpenSeeFaceUnitMm = 90.f / 0.632f;

/// OpenSeeFace's 66-point order by iBUG index: the same up to 47, then the
/// mouth as its 3D model orders it (outer upper 49-53, outer lower 55-59, the
/// corners 48 and 54 beside the inner lips 61-63 and 65-67).
extern const std::array<int, 66> kOpenSeeFaceFromIbug;

class OpenSeeFaceEncoder {
public:
    /// The model gives the 3D points (FaceModel::landmarkVertices on the fitted mesh).
    explicit OpenSeeFaceEncoder(std::shared_ptr<const FaceModel> model);

    /// Every face of the frame with a pose and landmarks, kOpenSeeFaceFaceBytes
    /// each, concatenated; empty when there is none (OpenSeeFace then sends
    /// nothing). `time` is the packet's timestamp (OpenSeeFace: Unix seconds).
    void encode(const FrameResult& frame, double time, std::vector<std::uint8_t>& out);

private:
    std::shared_ptr<const FaceModel> model_;
    std::vector<int> sent_vertices_;  ///< the 66 points' landmark vertices in OpenSeeFace's order, then the nose tip's
    std::vector<Vec3> sent_points_;   ///< those vertices on the face's mesh (reused)
};

}  // namespace facetrack::send
