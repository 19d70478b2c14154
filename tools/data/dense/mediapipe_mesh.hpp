#pragma once
// MediaPipe's face mesh as the teacher gives it (../shared/data/teacher/README.md):
// the canonical neutral mesh (468 vertices, cm, +y up, +z towards the viewer)
// and the per-image predictions of *_mesh.npy (478 points: the 468 mesh
// vertices, then 10 iris points). Another model's predictions, not ground truth.

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace facetrack::dense {

constexpr int kMeshVertexCount = 468;
constexpr int kTeacherPointCount = 478;

/// The canonical mesh's vertices (3 x 468) and triangles (0-based). Throws Error naming the file.
struct CanonicalMesh {
    Eigen::Matrix3Xd vertices;
    std::vector<std::array<int, 3>> triangles;
};
CanonicalMesh readCanonicalMesh(const std::string& objPath);

/// For each canonical vertex, its mirror image's vertex (x negated; itself on the midline).
std::vector<int> mirrorVertices(const Eigen::Matrix3Xd& canonical);

/// One row per line of the matching .jsonl: the record's key (300-W image path,
/// or teacherKey(clip, frame)), and its 468 mesh points in pixels.
struct TeacherMeshes {
    std::vector<std::string> keys;
    std::vector<bool> found;
    std::vector<int> width, height;    ///< of the image the teacher saw
    std::vector<std::int16_t> values;  ///< rows x 478 x 3, value / 16 = coordinate

    int rows() const { return static_cast<int>(keys.size()); }
    /// x, y of the 468 mesh vertices of row r, pixels (pixel-centre convention).
    Eigen::Matrix2Xd points(int row) const;
};
/// Throws Error naming the file when either is missing, malformed or their row counts differ.
TeacherMeshes readTeacherMeshes(const std::string& jsonlPath, const std::string& npyPath);

}  // namespace facetrack::dense
