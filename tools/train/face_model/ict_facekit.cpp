#include "ict_facekit.hpp"

#include "facetrack/error.hpp"

#include <Eigen/Core>

#include <cstring>
#include <fstream>
#include <regex>
#include <sstream>

namespace facetrack::tools {

namespace {
std::ifstream openOrThrow(const std::string& path, std::ios::openmode mode = std::ios::in) {
    std::ifstream in(path, mode);
    if (!in) throw Error("cannot open '" + path + "': " + std::strerror(errno));
    return in;
}
}  // namespace

ObjMesh readObj(const std::string& path) {
    auto in = openOrThrow(path);
    std::vector<float> v, vt;
    ObjMesh mesh;
    std::string line;
    int lineNo = 0;
    while (std::getline(in, line)) {
        ++lineNo;
        std::istringstream s(line);
        std::string tag;
        s >> tag;
        if (tag == "v") {
            float x, y, z;
            if (!(s >> x >> y >> z)) throw Error(path + ":" + std::to_string(lineNo) + ": bad vertex");
            v.insert(v.end(), {x, y, z});
        } else if (tag == "vt") {
            float u, w;
            if (!(s >> u >> w)) throw Error(path + ":" + std::to_string(lineNo) + ": bad uv");
            vt.insert(vt.end(), {u, w});
        } else if (tag == "f") {
            std::vector<std::uint32_t> ids, uvIds;
            std::string corner;
            while (s >> corner) {
                const auto slash = corner.find('/');
                ids.push_back(static_cast<std::uint32_t>(std::stoul(corner.substr(0, slash)) - 1));
                if (slash != std::string::npos && slash + 1 < corner.size() && corner[slash + 1] != '/') {
                    uvIds.push_back(static_cast<std::uint32_t>(std::stoul(corner.substr(slash + 1)) - 1));
                }
            }
            if (ids.size() < 3 || (!uvIds.empty() && uvIds.size() != ids.size())) {
                throw Error(path + ":" + std::to_string(lineNo) + ": bad face");
            }
            mesh.faces.push_back(std::move(ids));
            mesh.face_uvs.push_back(std::move(uvIds));
        }
    }
    mesh.vertices = Eigen::Map<Eigen::Matrix3Xf>(v.data(), 3, static_cast<Eigen::Index>(v.size() / 3));
    mesh.uvs = Eigen::Map<Eigen::Matrix2Xf>(vt.data(), 2, static_cast<Eigen::Index>(vt.size() / 2));
    return mesh;
}

NpyArray readNpy(const std::string& path) {
    auto in = openOrThrow(path, std::ios::binary);
    char magic[8];
    in.read(magic, 8);
    if (!in || std::memcmp(magic, "\x93NUMPY", 6) != 0) throw Error("'" + path + "' is not a .npy file");
    std::uint32_t headerLen = 0;
    if (magic[6] == 1) {
        std::uint16_t len16 = 0;
        in.read(reinterpret_cast<char*>(&len16), 2);
        headerLen = len16;
    } else {
        in.read(reinterpret_cast<char*>(&headerLen), 4);
    }
    std::string header(headerLen, '\0');
    in.read(header.data(), headerLen);

    std::smatch m;
    if (!std::regex_search(header, m, std::regex("'descr':\\s*'([<|]f[24])'"))) {
        throw Error("'" + path + "': only little-endian float16/float32 arrays are supported");
    }
    const bool half = m[1].str().back() == '2';
    if (header.find("'fortran_order': False") == std::string::npos) throw Error("'" + path + "': not C order");
    if (!std::regex_search(header, m, std::regex("'shape':\\s*\\(([^)]*)\\)"))) throw Error("'" + path + "': no shape");

    NpyArray array;
    std::size_t count = 1;
    std::stringstream dims(m[1].str());
    for (std::string d; std::getline(dims, d, ',');) {
        if (d.find_first_not_of(" ") == std::string::npos) continue;
        array.shape.push_back(std::stoul(d));
        count *= array.shape.back();
    }
    array.values.resize(count);
    if (half) {
        std::vector<Eigen::half> raw(count);
        in.read(reinterpret_cast<char*>(raw.data()), static_cast<std::streamsize>(count * 2));
        for (std::size_t i = 0; i < count; ++i) array.values[i] = static_cast<float>(raw[i]);
    } else {
        in.read(reinterpret_cast<char*>(array.values.data()), static_cast<std::streamsize>(count * 4));
    }
    if (!in) throw Error("'" + path + "': truncated array data");
    return array;
}

std::vector<std::string> readLines(const std::string& path) {
    auto in = openOrThrow(path);
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);) {
        line.erase(line.find_last_not_of(" \t\r") + 1);
        if (!line.empty()) lines.push_back(line);
    }
    return lines;
}

}  // namespace facetrack::tools
