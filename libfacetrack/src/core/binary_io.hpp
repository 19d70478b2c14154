#pragma once
// Versioned, checksummed binary model files, and bounds-checked readers and
// writers for their payloads. Every facetrack model file (face model, LBF
// landmarks, ...) uses this one container:
//
//   offset  0  char[8]   magic, names the kind of model
//   offset  8  uint32    format version
//   offset 12  uint32    reserved, 0
//   offset 16  uint64    payload size in bytes
//   offset 24  uint64    FNV-1a 64 checksum of the payload
//   offset 32  payload   little-endian, written by BinaryWriter
//
// All integers and floats are stored in the machine's byte order, which is
// little-endian on every platform facetrack targets (checked at compile time).

#include "facetrack/error.hpp"

#include <bit>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace facetrack::core {

static_assert(std::endian::native == std::endian::little, "facetrack model files are little-endian");

std::uint64_t fnv1a64(const void* data, std::size_t size);

class BinaryWriter {
public:
    template <class T>
    void put(const T& value) {
        static_assert(std::is_trivially_copyable_v<T>);
        bytes_.append(reinterpret_cast<const char*>(&value), sizeof(T));
    }
    template <class T>
    void putArray(const T* values, std::size_t count) {
        static_assert(std::is_trivially_copyable_v<T>);
        bytes_.append(reinterpret_cast<const char*>(values), sizeof(T) * count);
    }
    /// A uint64 element count, then the elements.
    template <class T>
    void putVector(const std::vector<T>& values) {
        put<std::uint64_t>(values.size());
        putArray(values.data(), values.size());
    }
    void putString(std::string_view s);
    /// Floats stored as IEEE half precision (2 bytes each).
    void putHalfs(const float* values, std::size_t count);

    const std::string& bytes() const { return bytes_; }

private:
    std::string bytes_;
};

/// Reads a payload. Any read past the end throws Error("<what>: ... truncated or corrupt").
class BinaryReader {
public:
    BinaryReader(std::string_view bytes, std::string what) : bytes_(bytes), what_(std::move(what)) {}

    template <class T>
    T get() {
        static_assert(std::is_trivially_copyable_v<T>);
        T value;
        std::memcpy(&value, take(sizeof(T)), sizeof(T));
        return value;
    }
    template <class T>
    void getArray(T* values, std::size_t count) {
        static_assert(std::is_trivially_copyable_v<T>);
        if (count > remaining() / sizeof(T)) fail("array of " + std::to_string(count) + " elements");
        if (count == 0) return;  // an empty vector's data() may be null, which memcpy must not get
        std::memcpy(values, take(sizeof(T) * count), sizeof(T) * count);
    }
    template <class T>
    std::vector<T> getVector() {
        const auto count = get<std::uint64_t>();
        if (count > remaining() / sizeof(T)) fail("array of " + std::to_string(count) + " elements");
        std::vector<T> values(count);
        getArray(values.data(), count);
        return values;
    }
    std::string getString();
    void getHalfs(float* values, std::size_t count);

    std::size_t remaining() const { return bytes_.size() - pos_; }
    /// Throws unless every byte was read: trailing bytes mean a format mismatch.
    void expectEnd() const;
    /// Throws Error naming the file and what was being read.
    [[noreturn]] void fail(const std::string& reading) const;

private:
    const char* take(std::size_t n);

    std::string_view bytes_;
    std::string what_;
    std::size_t pos_ = 0;
};

/// Writes the container around `payload`. Throws Error when the file cannot be written.
/// A whole file's bytes; `what` names it in the Error thrown when it cannot be opened or read.
std::string readFileBytes(const std::string& path, const std::string& what);

void writeModelFile(const std::string& path, std::string_view magic, std::uint32_t version, const std::string& payload);

/// Reads and validates the container; returns the payload. Throws Error naming
/// the file when it is missing, truncated, not of this kind (magic), of
/// another version, or fails the checksum. `kind` is a human name for messages.
std::string readModelFile(const std::string& path, std::string_view magic, std::uint32_t version, const std::string& kind);
/// The same for a format this build reads in versions oldest..newest; the
/// file's version goes to `fileVersion`.
std::string readModelFile(const std::string& path, std::string_view magic, std::uint32_t oldest, std::uint32_t newest,
                          const std::string& kind, std::uint32_t& fileVersion);

/// A model file opened for reading, the one way every model reader starts:
/// the container checked (readModelFile), the version it was written in, and a
/// reader over its payload whose errors name the file as "kind 'path'".
class ModelFileReader {
public:
    ModelFileReader(const std::string& path, std::string_view magic, std::uint32_t oldest, std::uint32_t newest, const std::string& kind)
        : payload_(readModelFile(path, magic, oldest, newest, kind, version_)), what_(kind + " '" + path + "'"), reader_(payload_, what_) {}
    ModelFileReader(const ModelFileReader&) = delete;  // the reader views the payload
    ModelFileReader& operator=(const ModelFileReader&) = delete;

    std::uint32_t version() const { return version_; }
    /// "kind 'path'": how errors about the file name it.
    const std::string& what() const { return what_; }
    BinaryReader& reader() { return reader_; }

private:
    std::uint32_t version_ = 0;
    std::string payload_;
    std::string what_;
    BinaryReader reader_;
};

}  // namespace facetrack::core
