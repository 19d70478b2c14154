#include "common/blendshape_teacher.hpp"

#include "common/teacher.hpp"

#include "facetrack/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
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
    for (int row = 2; std::getline(in, line); ++row) {
        const std::vector<std::string> f = split(line);
        if (f.size() > face && f[face] == "0") continue;  // no face found: no scores
        if (f.size() != header.size())
            throw Error(path + ", line " + std::to_string(row) + ": a row without " + std::to_string(header.size()) + " fields");
        const auto number = [&](std::size_t c) {
            char* end = nullptr;
            const float v = std::strtof(f[c].c_str(), &end);
            if (f[c].empty() || *end != '\0' || !std::isfinite(v))
                throw Error(path + ", line " + std::to_string(row) + ": '" + f[c] + "' in column '" + header[c] + "' is not a number");
            return v;
        };
        BlendshapeScores w{};
        for (std::size_t c = 0; c < f.size(); ++c)
            if (shape[c] >= 0) w[static_cast<std::size_t>(shape[c])] = number(c);
        const float frameNumber = number(frame);
        if (frameNumber < 0.f || frameNumber > 1e8f || frameNumber != std::floor(frameNumber))
            throw Error(path + ", line " + std::to_string(row) + ": frame '" + f[frame] + "' is not a frame number");
        out[teacherKey(f[clip], static_cast<int>(frameNumber))] = w;
    }
    return out;
}

}  // namespace facetrack::tools
