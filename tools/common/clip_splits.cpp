#include "common/clip_splits.hpp"

#include "facetrack/error.hpp"

#include <fstream>

namespace facetrack::tools {

namespace {

/// (clip, split) per line, in order.
std::vector<std::pair<std::string, std::string>> readLines(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw Error("cannot read '" + path + "' (run from the repository's root)");
    std::vector<std::pair<std::string, std::string>> out;
    for (std::string line; std::getline(in, line);) {
        if (line.empty() || line[0] == '#' || line.rfind("clip,", 0) == 0) continue;
        const auto a = line.find(','), b = line.find(',', a == std::string::npos ? a : a + 1);
        if (a == std::string::npos || b == std::string::npos) throw Error(path + ": expected clip,split,person in '" + line + "'");
        const std::string split = line.substr(a + 1, b - a - 1);
        if (split != "heldout" && split != "validation") throw Error(path + ": unknown split '" + split + "'");
        out.emplace_back(line.substr(0, a), split);
    }
    return out;
}

}  // namespace

std::map<std::string, std::string> readClipSplits(const std::string& path) {
    std::map<std::string, std::string> out;
    for (const auto& [clip, split] : readLines(path)) out[clip] = split;
    return out;
}

std::vector<std::string> clipsOfSplit(const std::string& split, const std::string& path) {
    std::vector<std::string> out;
    for (const auto& [clip, s] : readLines(path))
        if (s == split) out.push_back(clip);
    return out;
}

}  // namespace facetrack::tools
