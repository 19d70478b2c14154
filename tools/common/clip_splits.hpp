#pragma once
// data/clip_splits.csv: the people no net trains on, by clip (../shared/data/clips file names):
// "heldout" (no trainer reads them; the figures are read on them) or "validation" (a trainer
// chooses its epoch on them). A clip the file does not name is training material.

#include <map>
#include <string>
#include <vector>

namespace facetrack::tools {

/// Clip file name -> "heldout" or "validation". Throws Error when the file cannot be read or a
/// line is not clip,split,person with a known split.
std::map<std::string, std::string> readClipSplits(const std::string& path = "data/clip_splits.csv");

/// The clips of one split, in the file's order.
std::vector<std::string> clipsOfSplit(const std::string& split, const std::string& path = "data/clip_splits.csv");

}  // namespace facetrack::tools
