#include "core/binary_io.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace facetrack::core {
namespace {

using test::tempPath;

std::string slurp(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void spit(const std::string& path, const std::string& bytes) { std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes; }

/// The Error message thrown by f, or "" if none.
template <class F>
std::string errorOf(F&& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

TEST(BinaryIo, WriterReaderRoundTrip) {
    BinaryWriter w;
    w.put<std::int32_t>(-7);
    w.put<double>(2.5);
    w.putString("jawOpen");
    w.putVector(std::vector<std::uint32_t>{1, 2, 3});
    const float halfs[3] = {0.5f, -1.25f, 1000.f};
    w.putHalfs(halfs, 3);

    BinaryReader r(w.bytes(), "test");
    EXPECT_EQ(r.get<std::int32_t>(), -7);
    EXPECT_EQ(r.get<double>(), 2.5);
    EXPECT_EQ(r.getString(), "jawOpen");
    EXPECT_EQ(r.getVector<std::uint32_t>(), (std::vector<std::uint32_t>{1, 2, 3}));
    float back[3];
    r.getHalfs(back, 3);
    EXPECT_EQ(back[0], 0.5f);  // exactly representable in half precision
    EXPECT_EQ(back[1], -1.25f);
    EXPECT_EQ(back[2], 1000.f);
    EXPECT_NO_THROW(r.expectEnd());
}

TEST(BinaryIo, ReadingPastTheEndThrowsWithContext) {
    BinaryWriter w;
    w.put<std::uint64_t>(1'000'000);  // a vector length with no elements behind it
    BinaryReader r(w.bytes(), "model 'x.bin'");
    const std::string msg = errorOf([&] { r.getVector<float>(); });
    EXPECT_NE(msg.find("model 'x.bin'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;
}

/// Found by fuzz_model_files (fuzz/corpus/fuzz_model_files/regression-empty-vector):
/// an empty vector handed memcpy its null data() (undefined behaviour, UBSan).
TEST(BinaryIo, EmptyVectorsAndArraysRoundTrip) {
    BinaryWriter w;
    w.putVector(std::vector<float>{});
    w.putVector(std::vector<std::uint8_t>{});
    w.putString("");
    BinaryReader r(w.bytes(), "test");
    EXPECT_TRUE(r.getVector<float>().empty());
    EXPECT_TRUE(r.getVector<std::uint8_t>().empty());
    EXPECT_EQ(r.getString(), "");
    r.getArray<float>(nullptr, 0);
    EXPECT_NO_THROW(r.expectEnd());
}

TEST(BinaryIo, TrailingBytesAreAnError) {
    BinaryWriter w;
    w.put<std::uint32_t>(1);
    w.put<std::uint32_t>(2);
    BinaryReader r(w.bytes(), "test");
    r.get<std::uint32_t>();
    EXPECT_THROW(r.expectEnd(), Error);
}

class ModelFileTest : public ::testing::Test {
protected:
    const std::string path = tempPath("container.bin");
    const std::string payload = std::string(1000, 'x') + "payload";
    void SetUp() override { writeModelFile(path, "TESTMODL", 3, payload); }
    void TearDown() override { std::filesystem::remove(path); }
    std::string readError() {
        return errorOf([&] { readModelFile(path, "TESTMODL", 3, "test model"); });
    }
};

TEST_F(ModelFileTest, RoundTrip) { EXPECT_EQ(readModelFile(path, "TESTMODL", 3, "test model"), payload); }

TEST_F(ModelFileTest, MissingFileNamesTheFile) {
    const std::string msg = errorOf([&] { readModelFile(path + ".nope", "TESTMODL", 3, "test model"); });
    EXPECT_NE(msg.find(path + ".nope"), std::string::npos) << msg;
    EXPECT_NE(msg.find("cannot open"), std::string::npos) << msg;
}

TEST_F(ModelFileTest, TruncatedFileIsReported) {
    const std::string bytes = slurp(path);
    for (std::size_t keep : {std::size_t(0), std::size_t(10), bytes.size() - 1}) {
        spit(path, bytes.substr(0, keep));
        const std::string msg = readError();
        EXPECT_NE(msg.find("truncated"), std::string::npos) << "keep " << keep << ": " << msg;
        EXPECT_NE(msg.find(path), std::string::npos) << msg;
    }
}

TEST_F(ModelFileTest, CorruptPayloadFailsTheChecksum) {
    std::string bytes = slurp(path);
    bytes[bytes.size() / 2] ^= 0x10;
    spit(path, bytes);
    const std::string msg = readError();
    EXPECT_NE(msg.find("checksum"), std::string::npos) << msg;
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
}

TEST_F(ModelFileTest, WrongMagicAndVersionAreReported) {
    EXPECT_NE(errorOf([&] { readModelFile(path, "OTHERMDL", 3, "test model"); }).find("wrong magic"), std::string::npos);
    const std::string msg = errorOf([&] { readModelFile(path, "TESTMODL", 4, "test model"); });
    EXPECT_NE(msg.find("format version 3"), std::string::npos) << msg;
    EXPECT_NE(msg.find("reads version 4"), std::string::npos) << msg;
}

}  // namespace
}  // namespace facetrack::core
