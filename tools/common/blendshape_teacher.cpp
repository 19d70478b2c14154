#include "common/blendshape_teacher.hpp"

#include "common/teacher.hpp"

#include "facetrack/error.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>
#include <vector>

namespace facetrack::tools {

std::map<std::string, BlendshapeScores> readBlendshapeTeacher(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw Error("cannot read the blendshape teacher '" + path + "'");
    auto split = [](const std::string& line) {
        std::vector<std::string> fields;
        std::stringstream s(line);
        for (std::string f; std::getline(s, f, ',');) fields.push_back(f);
        return fields;
    };
    std::string line;
    std::getline(in, line);
    const std::vector<std::string> header = split(line);
    std::vector<int> shape(header.size(), -1);
    for (std::size_t c = 0; c < header.size(); ++c) shape[c] = arkitIndex(header[c]);
    const auto column = [&](const std::string& name) {
        const auto it = std::find(header.begin(), header.end(), name);
        if (it == header.end()) throw Error(path + ": no column '" + name + "'");
        return static_cast<std::size_t>(it - header.begin());
    };
    const std::size_t clip = column("clip"), frame = column("frame"), face = column("face");
    std::map<std::string, BlendshapeScores> out;
    while (std::getline(in, line)) {
        const std::vector<std::string> f = split(line);
        if (f.size() > face && f[face] == "0") continue;  // no face found: no scores
        if (f.size() != header.size()) throw Error(path + ": a row without " + std::to_string(header.size()) + " fields");
        BlendshapeScores w{};
        for (std::size_t c = 0; c < f.size(); ++c)
            if (shape[c] >= 0) w[static_cast<std::size_t>(shape[c])] = std::stof(f[c]);
        out[teacherKey(f[clip], std::stoi(f[frame]))] = w;
    }
    return out;
}

}  // namespace facetrack::tools
