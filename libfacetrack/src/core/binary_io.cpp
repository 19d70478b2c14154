#include "core/binary_io.hpp"

#include <Eigen/Core>

#include <fstream>
#include <iterator>

namespace facetrack::core {

namespace {
constexpr std::size_t kHeaderSize = 32;
constexpr std::size_t kMagicSize = 8;

std::string paddedMagic(std::string_view magic) {
    std::string m(magic.substr(0, kMagicSize));
    m.resize(kMagicSize, '\0');
    return m;
}
}  // namespace

std::uint64_t fnv1a64(const void* data, std::size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    std::uint64_t hash = 14695981039346656037ull;
    for (std::size_t i = 0; i < size; ++i) {
        hash ^= p[i];
        hash *= 1099511628211ull;
    }
    return hash;
}

void BinaryWriter::putString(std::string_view s) {
    put<std::uint32_t>(static_cast<std::uint32_t>(s.size()));
    bytes_.append(s.data(), s.size());
}

void BinaryWriter::putHalfs(const float* values, std::size_t count) {
    for (std::size_t i = 0; i < count; ++i) put(Eigen::half(values[i]).x);
}

std::string BinaryReader::getString() {
    const auto size = get<std::uint32_t>();
    if (size > remaining()) fail("string of " + std::to_string(size) + " bytes");
    return std::string(take(size), size);
}

void BinaryReader::getHalfs(float* values, std::size_t count) {
    if (count > remaining() / 2) fail("array of " + std::to_string(count) + " half floats");
    for (std::size_t i = 0; i < count; ++i) {
        values[i] = static_cast<float>(Eigen::numext::bit_cast<Eigen::half>(get<std::uint16_t>()));
    }
}

void BinaryReader::expectEnd() const {
    if (remaining() != 0) {
        throw Error(what_ + ": corrupt: " + std::to_string(remaining()) + " unexpected trailing bytes");
    }
}

void BinaryReader::fail(const std::string& reading) const {
    throw Error(what_ + ": truncated or corrupt (reading " + reading + " at byte " + std::to_string(pos_) + " of " +
                std::to_string(bytes_.size()) + ")");
}

const char* BinaryReader::take(std::size_t n) {
    if (n > remaining()) fail(std::to_string(n) + " bytes");
    const char* p = bytes_.data() + pos_;
    pos_ += n;
    return p;
}

void writeModelFile(const std::string& path, std::string_view magic, std::uint32_t version, const std::string& payload) {
    BinaryWriter header;
    const std::string m = paddedMagic(magic);
    header.putArray(m.data(), m.size());
    header.put<std::uint32_t>(version);
    header.put<std::uint32_t>(0);
    header.put<std::uint64_t>(payload.size());
    header.put<std::uint64_t>(fnv1a64(payload.data(), payload.size()));

    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    if (!out) throw Error("cannot write '" + path + "': " + std::strerror(errno));
    out.write(header.bytes().data(), static_cast<std::streamsize>(header.bytes().size()));
    out.write(payload.data(), static_cast<std::streamsize>(payload.size()));
    if (!out.flush()) throw Error("cannot write '" + path + "': " + std::strerror(errno));
}

std::string readModelFile(const std::string& path, std::string_view magic, std::uint32_t version, const std::string& kind) {
    std::uint32_t fileVersion = 0;
    return readModelFile(path, magic, version, version, kind, fileVersion);
}

std::string readFileBytes(const std::string& path, const std::string& what) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error("cannot open " + what + ": " + std::strerror(errno));
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw Error("cannot read " + what + ": " + std::strerror(errno));
    return bytes;
}

std::string readModelFile(const std::string& path, std::string_view magic, std::uint32_t oldest, std::uint32_t newest,
                          const std::string& kind, std::uint32_t& fileVersion) {
    const std::string what = kind + " '" + path + "'";
    const std::string bytes = readFileBytes(path, what);

    if (bytes.size() < kHeaderSize) {
        throw Error(what + ": truncated (" + std::to_string(bytes.size()) + " bytes, shorter than the header)");
    }
    BinaryReader header(std::string_view(bytes).substr(0, kHeaderSize), what);
    std::string fileMagic(kMagicSize, '\0');
    header.getArray(fileMagic.data(), kMagicSize);
    if (fileMagic != paddedMagic(magic)) throw Error(what + ": not a " + kind + " file (wrong magic number)");
    fileVersion = header.get<std::uint32_t>();
    if (fileVersion < oldest || fileVersion > newest) {
        const std::string readable = oldest == newest ? "version " + std::to_string(newest)
                                                      : "versions " + std::to_string(oldest) + " to " + std::to_string(newest);
        throw Error(what + ": format version " + std::to_string(fileVersion) + ", this build reads " + readable +
                    "; regenerate the file (see models/README.md)");
    }
    header.get<std::uint32_t>();
    const auto payloadSize = header.get<std::uint64_t>();
    const auto checksum = header.get<std::uint64_t>();
    if (bytes.size() - kHeaderSize != payloadSize) {
        throw Error(what + ": truncated or padded (payload " + std::to_string(bytes.size() - kHeaderSize) + " bytes, header says " +
                    std::to_string(payloadSize) + ")");
    }
    if (fnv1a64(bytes.data() + kHeaderSize, payloadSize) != checksum) {
        throw Error(what + ": corrupt (checksum mismatch)");
    }
    return bytes.substr(kHeaderSize);
}

}  // namespace facetrack::core
