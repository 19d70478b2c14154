#include "dense/label_table.hpp"

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
        if (c.size() != header.size()) throw Error(path + ":" + std::to_string(number) + ": expected " + std::to_string(header.size()) + " cells");
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

}  // namespace facetrack::dense
