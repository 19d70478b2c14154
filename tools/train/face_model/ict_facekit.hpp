#pragma once
// Reading ICT-FaceKit's FaceXModel folder (as shared/models/ict-facekit ships it).

#include <Eigen/Core>

#include <string>
#include <vector>

namespace facetrack::tools {

struct ObjMesh {
    Eigen::Matrix3Xf vertices;
    Eigen::Matrix2Xf uvs;
    std::vector<std::vector<std::uint32_t>> faces;     ///< polygon vertex ids, 0-based
    std::vector<std::vector<std::uint32_t>> face_uvs;  ///< polygon uv ids, 0-based
};

/// Reads v, vt and f (v/vt or v/vt/vn) lines. Throws facetrack::Error on malformed input.
ObjMesh readObj(const std::string& path);

/// A float16 or float32 little-endian C-order .npy array, as float.
struct NpyArray {
    std::vector<std::size_t> shape;
    std::vector<float> values;
};
NpyArray readNpy(const std::string& path);

/// Lines of a text file, trailing blanks stripped, empty lines dropped.
std::vector<std::string> readLines(const std::string& path);

}  // namespace facetrack::tools
