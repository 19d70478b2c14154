#include "core/pts.hpp"

#include "facetrack/error.hpp"

#include <fstream>
#include <sstream>

namespace facetrack::core {

Shape2 readPts(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw Error("cannot open landmark file '" + path + "'");
    std::string line;
    std::size_t expected = 0;
    bool inPoints = false;
    std::vector<float> points;
    while (std::getline(in, line)) {
        if (line.rfind("n_points:", 0) == 0) {
            expected = std::stoul(line.substr(9));
        } else if (line.rfind("{", 0) == 0) {
            inPoints = true;
        } else if (line.rfind("}", 0) == 0) {
            break;
        } else if (inPoints) {
            std::istringstream s(line);
            float x, y;
            if (!(s >> x >> y)) throw Error("'" + path + "': malformed point line '" + line + "'");
            points.insert(points.end(), {x - 1.f, y - 1.f});
        }
    }
    const std::size_t count = points.size() / 2;
    if (count == 0 || (expected != 0 && count != expected)) {
        throw Error("'" + path + "': expected " + std::to_string(expected) + " points, read " + std::to_string(count));
    }
    return Eigen::Map<const Shape2>(points.data(), 2, static_cast<Eigen::Index>(count));
}

void writePts(const std::string& path, const Shape2& points) {
    std::ofstream out(path);
    out << "version: 1\nn_points: " << points.cols() << "\n{\n";
    out.precision(7);
    for (Eigen::Index i = 0; i < points.cols(); ++i) out << points(0, i) + 1.f << ' ' << points(1, i) + 1.f << '\n';
    out << "}\n";
    if (!out) throw Error("cannot write landmark file '" + path + "'");
}

}  // namespace facetrack::core
