#include "common/npy_writer.hpp"

#include "facetrack/error.hpp"

#include <filesystem>

namespace facetrack::tools {

NpyWriter::NpyWriter(const std::string& path, std::string descr, std::string rowShape)
    : path_(path), descr_(std::move(descr)), row_shape_(std::move(rowShape)), out_(path + ".part", std::ios::binary) {
    if (!out_) throw Error("cannot write '" + path + "'");
}

void NpyWriter::add(const void* row, std::size_t bytes) {
    out_.write(static_cast<const char*>(row), static_cast<std::streamsize>(bytes));
    ++rows_;
}

void NpyWriter::finish() {
    out_.close();
    std::string header = "{'descr': '" + descr_ + "', 'fortran_order': False, 'shape': (" + std::to_string(rows_) + ", " + row_shape_ +
                         "), }";
    header.resize(((header.size() + 11) / 64 + 1) * 64 - 11, ' ');  // the format pads the header to 64 bytes
    header += '\n';
    std::ofstream out(path_, std::ios::binary);
    out.write("\x93NUMPY\x01\x00", 8);
    const char length[2] = {static_cast<char>(header.size() & 0xff), static_cast<char>(header.size() >> 8)};
    out.write(length, 2);
    out << header;
    std::ifstream body(path_ + ".part", std::ios::binary);
    if (body.peek() != std::ifstream::traits_type::eof()) out << body.rdbuf();  // an empty buffer would set failbit: no rows
    if (!out) throw Error("cannot write '" + path_ + "'");
    std::filesystem::remove(path_ + ".part");
}

}  // namespace facetrack::tools
