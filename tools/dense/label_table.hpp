#pragma once
// label_dense's CSV files (faces300w.csv, clips.csv) read back: one row per
// crop or frame, its key (300-W path or "CLIP#FRAME"), split and numbers.

#include <map>
#include <string>
#include <vector>

namespace facetrack::dense {

struct LabelTable {
    std::vector<std::string> columns;  ///< the numeric columns' names, after key and split
    struct Row {
        std::string key, split;
        std::vector<double> values;  ///< in `columns` order
    };
    std::vector<Row> rows;

    /// Index into Row::values, or -1.
    int column(const std::string& name) const;
};

/// Throws Error naming the file and line when it is missing or malformed.
LabelTable readLabelTable(const std::string& path);

}  // namespace facetrack::dense
