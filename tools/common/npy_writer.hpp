#pragma once
// Writes a NumPy .npy file row by row (the training scripts read them with
// numpy.load); the header, which holds the row count, is written last.

#include <opencv2/core.hpp>

#include <fstream>
#include <string>

namespace facetrack::tools {

class NpyWriter {
public:
    /// `descr`: numpy's type string ("|u1", "<f4"); `rowShape`: the shape of one row, e.g. "64, 64".
    /// Throws Error when the file cannot be written.
    NpyWriter(const std::string& path, std::string descr, std::string rowShape);
    void add(const void* row, std::size_t bytes);
    /// A continuous matrix's bytes as one row.
    void add(const cv::Mat& row) { add(row.data, row.total() * row.elemSize()); }
    int rows() const { return rows_; }
    /// Writes the header and the rows to the path (they go to PATH.part until then).
    void finish();

private:
    std::string path_, descr_, row_shape_;
    std::ofstream out_;
    int rows_ = 0;
};

}  // namespace facetrack::tools
