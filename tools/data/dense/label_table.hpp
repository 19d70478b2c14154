#pragma once
// label_dense's CSV files (faces300w.csv, clips.csv) read back: one row per
// crop or frame, its key (300-W path or "CLIP#FRAME"), split and numbers;
// and a row's face as the fit's parameters.

#include "fit/pose.hpp"

#include <Eigen/Core>

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

/// Where a row's pose, identity and expressions are.
struct LabelColumns {
    int omega = -1, translation = -1, identity = -1, identity_count = 0;
    std::vector<int> expressions;  ///< per name asked for, its column
};

/// Throws Error when the table lacks the pose, identity or one of `expressionNames`.
LabelColumns labelColumns(const LabelTable& table, const std::vector<std::string>& expressionNames);

/// The row's pose and expressions (in the names' order).
fit::FaceParams labelParams(const LabelColumns& columns, const LabelTable::Row& row);
Eigen::VectorXd labelIdentity(const LabelColumns& columns, const LabelTable::Row& row);

}  // namespace facetrack::dense
