#pragma once
// The face model as plain data (internal). The public facetrack::FaceModel
// wraps one of these, immutable once loaded.
//
// Model (ICT-FaceKit, centimetres, model frame of result.hpp):
//   V(a, b) = neutral + B_id a + sum_j b_j D_j
// with B_id the identity basis (3V x K, a ~ N(0, I)) and D_j the sparse
// expression deltas, b_j in [0, 1].

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace facetrack::model {

constexpr int kLandmarkCount = 68;
constexpr int kContourLandmarkCount = 17;  // iBUG 0..16, the jaw line

using Triangle = std::array<std::uint32_t, 3>;

struct SparseBlendshape {
    std::string name;
    std::vector<std::uint32_t> vertices;  ///< ascending vertex ids that move
    Eigen::Matrix3Xf deltas;              ///< 3 x vertices.size(), cm
};

struct Eyeball {
    std::uint32_t first_vertex = 0;  ///< sclera and iris vertices, inclusive range
    std::uint32_t last_vertex = 0;
    Eigen::Vector3f centre = Eigen::Vector3f::Zero();         ///< rotation centre, cm
    Eigen::Vector3f optical_axis = Eigen::Vector3f::UnitZ();  ///< unit, at rest
    float radius = 0.f;                                       ///< eyeball (sclera sphere) radius, cm
    float iris_radius = 0.f;                                  ///< cm
};

struct FaceModelData {
    Eigen::Matrix3Xf neutral;  ///< 3 x V
    /// 3V x K; row 3v + c is coordinate c of vertex v. Column k is identity mode k,
    /// scaled so that a_k ~ N(0, 1).
    Eigen::MatrixXf identity_basis;
    float identity_explained_variance = 0.f;  ///< on the face region, of the source's full basis
    std::uint32_t face_vertex_count = 0;      ///< vertices [0, n) are the face skin region

    std::vector<SparseBlendshape> expressions;

    std::vector<Triangle> triangles;
    Eigen::Matrix2Xf uvs;                ///< 2 x U texture coordinates
    std::vector<Triangle> triangle_uvs;  ///< per triangle corner, indices into uvs

    std::array<std::uint32_t, kLandmarkCount> landmark_vertices{};
    /// For each jaw landmark 0..16, the vertices it may slide to as the head
    /// turns, ordered from the frontal position outwards.
    std::array<std::vector<std::uint32_t>, kContourLandmarkCount> contour_candidates;

    Eyeball left_eye;   ///< subject's left (+x)
    Eyeball right_eye;  ///< subject's right (-x)

    int vertexCount() const { return static_cast<int>(neutral.cols()); }
    int identityCount() const { return static_cast<int>(identity_basis.cols()); }
};

constexpr char kFaceModelMagic[] = "FTFACEMD";
constexpr std::uint32_t kFaceModelVersion = 1;

/// Throws facetrack::Error (prefixed by `what`) unless every index and size is consistent.
void validate(const FaceModelData& data, const std::string& what);

std::string serialize(const FaceModelData& data);
FaceModelData deserialize(const std::string& payload, const std::string& what);

void writeFaceModel(const std::string& path, const FaceModelData& data);
FaceModelData readFaceModel(const std::string& path);

}  // namespace facetrack::model
