#include "data/dense/mediapipe_mesh.hpp"

#include "common/teacher.hpp"

#include "facetrack/error.hpp"

#include <nlohmann/json.hpp>

#include <array>
#include <cstring>
#include <fstream>
#include <sstream>

namespace facetrack::dense {

CanonicalMesh readCanonicalMesh(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw Error("cannot read the canonical mesh '" + path + "'");
    std::vector<Eigen::Vector3d> vertices;
    CanonicalMesh mesh;
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream s(line);
        std::string tag;
        s >> tag;
        if (tag == "v") {
            Eigen::Vector3d v;
            s >> v.x() >> v.y() >> v.z();
            if (!s) throw Error(path + ": bad vertex line '" + line + "'");
            vertices.push_back(v);
        } else if (tag == "f") {
            std::array<int, 3> t{};
            for (int& corner : t) {
                std::string c;
                s >> c;
                corner = std::atoi(c.c_str()) - 1;  // "v/vt": the vertex index comes first
            }
            mesh.triangles.push_back(t);
        }
    }
    if (vertices.size() != kMeshVertexCount) {
        throw Error(path + ": " + std::to_string(vertices.size()) + " vertices, expected " + std::to_string(kMeshVertexCount));
    }
    for (const auto& t : mesh.triangles) {
        for (const int v : t)
            if (v < 0 || v >= kMeshVertexCount) throw Error(path + ": triangle index out of range");
    }
    mesh.vertices.resize(3, kMeshVertexCount);
    for (int i = 0; i < kMeshVertexCount; ++i) mesh.vertices.col(i) = vertices[static_cast<std::size_t>(i)];
    return mesh;
}

std::vector<int> mirrorVertices(const Eigen::Matrix3Xd& canonical) {
    std::vector<int> mirror(static_cast<std::size_t>(canonical.cols()));
    for (Eigen::Index i = 0; i < canonical.cols(); ++i) {
        const Eigen::Vector3d image(-canonical(0, i), canonical(1, i), canonical(2, i));
        Eigen::Index nearest = 0;
        (canonical.colwise() - image).colwise().squaredNorm().minCoeff(&nearest);
        mirror[static_cast<std::size_t>(i)] = static_cast<int>(nearest);
    }
    return mirror;
}

namespace {

/// The shape of a numpy v1 file of little-endian int16 in C order; leaves `in` at the data.
std::vector<long> readNpyHeader(std::ifstream& in, const std::string& path) {
    char magic[8];
    in.read(magic, 8);
    if (!in || std::memcmp(magic, "\x93NUMPY", 6) != 0) throw Error(path + ": not a .npy file");
    unsigned char lengthBytes[2];
    in.read(reinterpret_cast<char*>(lengthBytes), 2);
    std::string header(lengthBytes[0] | (lengthBytes[1] << 8), '\0');
    in.read(header.data(), static_cast<std::streamsize>(header.size()));
    if (!in) throw Error(path + ": truncated .npy header");
    if (header.find("'<i2'") == std::string::npos || header.find("'fortran_order': False") == std::string::npos) {
        throw Error(path + ": expected little-endian int16 in C order");
    }
    const auto open = header.find("'shape': (");
    if (open == std::string::npos) throw Error(path + ": no shape in the .npy header");
    std::vector<long> shape;
    std::istringstream dims(header.substr(open + 10, header.find(')', open) - open - 10));
    std::string dim;
    while (std::getline(dims, dim, ',')) {
        if (dim.find_first_not_of(' ') != std::string::npos) shape.push_back(std::stol(dim));
    }
    return shape;
}

}  // namespace

TeacherMeshes readTeacherMeshes(const std::string& jsonlPath, const std::string& npyPath) {
    TeacherMeshes m;
    std::ifstream lines(jsonlPath);
    if (!lines) throw Error("cannot read teacher labels '" + jsonlPath + "'");
    std::string line;
    while (std::getline(lines, line)) {
        if (line.empty()) continue;
        const auto j = nlohmann::json::parse(line);
        m.keys.push_back(j.contains("image") ? j.at("image").get<std::string>()
                                             : tools::teacherKey(j.at("clip").get<std::string>(), j.at("frame").get<int>()));
        m.found.push_back(j.value("found", false));
        m.width.push_back(j.value("width", 0));
        m.height.push_back(j.value("height", 0));
    }
    std::ifstream in(npyPath, std::ios::binary);
    if (!in) throw Error("cannot read the teacher meshes '" + npyPath + "'");
    const auto shape = readNpyHeader(in, npyPath);
    if (shape.size() != 3 || shape[0] != m.rows() || shape[1] != kTeacherPointCount || shape[2] != 3) {
        throw Error(npyPath + ": shape does not match " + std::to_string(m.rows()) + " lines of " + jsonlPath + " x 478 x 3");
    }
    m.values.resize(static_cast<std::size_t>(m.rows()) * kTeacherPointCount * 3);
    in.read(reinterpret_cast<char*>(m.values.data()), static_cast<std::streamsize>(m.values.size() * sizeof(std::int16_t)));
    if (!in) throw Error(npyPath + ": truncated");
    return m;
}

Eigen::Matrix2Xd TeacherMeshes::points(int row) const {
    Eigen::Matrix2Xd p(2, kMeshVertexCount);
    const std::int16_t* v = values.data() + static_cast<std::size_t>(row) * kTeacherPointCount * 3;
    for (int i = 0; i < kMeshVertexCount; ++i) p.col(i) << v[3 * i] / 16.0, v[3 * i + 1] / 16.0;
    return p;
}

}  // namespace facetrack::dense
