#include "data/dense/label_table.hpp"

#include "facetrack/error.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>

namespace facetrack::dense {

int LabelTable::column(const std::string& name) const {
    const auto it = std::find(columns.begin(), columns.end(), name);
    return it == columns.end() ? -1 : static_cast<int>(it - columns.begin());
}

namespace {
std::vector<std::string> cells(const std::string& line) {
    std::vector<std::string> out;
    std::stringstream s(line);
    for (std::string cell; std::getline(s, cell, ',');) out.push_back(cell);
    return out;
}
}  // namespace

LabelTable readLabelTable(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw Error("cannot read dense labels '" + path + "' (build/tools/label_dense makes them)");
    std::string line;
    if (!std::getline(in, line)) throw Error(path + ": empty");
    const auto header = cells(line);
    if (header.size() < 3 || header[0] != "key" || header[1] != "split") throw Error(path + ": not a label_dense table");
    LabelTable t;
    t.columns.assign(header.begin() + 2, header.end());
    for (int number = 2; std::getline(in, line); ++number) {
        const auto c = cells(line);
        if (c.size() != header.size())
            throw Error(path + ":" + std::to_string(number) + ": expected " + std::to_string(header.size()) + " cells");
        LabelTable::Row row{c[0], c[1], {}};
        row.values.reserve(t.columns.size());
        try {
            for (std::size_t k = 2; k < c.size(); ++k) row.values.push_back(std::stod(c[k]));
        } catch (const std::exception&) {
            throw Error(path + ":" + std::to_string(number) + ": not a number");
        }
        t.rows.push_back(std::move(row));
    }
    return t;
}

LabelColumns labelColumns(const LabelTable& t, const std::vector<std::string>& expressionNames) {
    LabelColumns c;
    c.omega = t.column("omega_x");
    c.translation = t.column("t_x_cm");
    c.identity = t.column("id0");
    if (c.omega < 0 || c.translation < 0 || c.identity < 0) throw Error("the labels have no pose or identity columns");
    while (t.column("id" + std::to_string(c.identity_count)) == c.identity + c.identity_count) ++c.identity_count;
    for (const auto& n : expressionNames) {
        c.expressions.push_back(t.column(n));
        if (c.expressions.back() < 0) throw Error("the labels have no column '" + n + "'");
    }
    return c;
}

fit::FaceParams labelParams(const LabelColumns& c, const LabelTable::Row& row) {
    fit::FaceParams p;
    for (int k = 0; k < 3; ++k) p.pose[k] = row.values[static_cast<std::size_t>(c.omega + k)];
    for (int k = 0; k < 3; ++k) p.pose[3 + k] = row.values[static_cast<std::size_t>(c.translation + k)];
    p.expression.resize(static_cast<Eigen::Index>(c.expressions.size()));
    for (std::size_t k = 0; k < c.expressions.size(); ++k)
        p.expression[static_cast<Eigen::Index>(k)] = row.values[static_cast<std::size_t>(c.expressions[k])];
    return p;
}

Eigen::VectorXd labelIdentity(const LabelColumns& c, const LabelTable::Row& row) {
    Eigen::VectorXd a(c.identity_count);
    for (int k = 0; k < c.identity_count; ++k) a[k] = row.values[static_cast<std::size_t>(c.identity + k)];
    return a;
}

}  // namespace facetrack::dense
