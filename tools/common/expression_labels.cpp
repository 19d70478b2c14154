#include "common/expression_labels.hpp"

#include "facetrack/error.hpp"

#include <fstream>
#include <sstream>

namespace facetrack::tools {

std::vector<LabelledSegment> readExpressionLabels(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw Error("cannot read labels '" + path + "'");
    std::vector<LabelledSegment> segments;
    int number = 0;
    for (std::string line; std::getline(in, line);) {
        ++number;
        if (line.empty() || line[0] == '#' || line.rfind("clip,", 0) == 0) continue;
        const std::string where = path + ":" + std::to_string(number);
        std::stringstream s(line);
        LabelledSegment seg;
        std::string first, last;
        if (!std::getline(s, seg.clip, ',') || !std::getline(s, first, ',') || !std::getline(s, last, ',') || !std::getline(s, seg.label))
            throw Error(where + ": expected clip,first,last,label");
        try {
            seg.first = std::stoi(first);
            seg.last = std::stoi(last);
        } catch (const std::exception&) {
            throw Error(where + ": frames must be numbers");
        }
        if (seg.first < 0 || seg.last < seg.first) throw Error(where + ": expected 0 <= first <= last");
        segments.push_back(seg);
    }
    return segments;
}

}  // namespace facetrack::tools
