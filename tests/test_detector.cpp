#include "core/image.hpp"
#include "core/pts.hpp"
#include "facetrack/detector.hpp"
#include "facetrack/error.hpp"
#include "facetrack/version.hpp"
#include "test_support.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace facetrack {
namespace {

namespace fs = std::filesystem;

/// Sets an environment variable for the scope of the object.
class ScopedEnv {
public:
    ScopedEnv(const char* name, const std::string& value) : name_(name) {
        if (const char* old = std::getenv(name)) old_ = old;
        ::setenv(name, value.c_str(), 1);
    }
    ~ScopedEnv() {
        if (old_) ::setenv(name_, old_->c_str(), 1);
        else ::unsetenv(name_);
    }

private:
    const char* name_;
    std::optional<std::string> old_;
};

DetectorConfig configOf(DetectorKind kind) {
    DetectorConfig config;
    config.kind = kind;
    return config;
}

struct AnnotatedFace {
    cv::Mat image;
    core::Shape2 points;
};

AnnotatedFace sampleFace() {
    const std::string stem = test::sharedDir() + "/data/faces300w/helen/testset/296814969_3";
    return {cv::imread(stem + ".jpg"), core::readPts(stem + ".pts")};
}

bool boxContains(const Box& b, const Eigen::Vector2f& p) { return p.x() >= b.x0 && p.x() <= b.x1 && p.y() >= b.y0 && p.y() <= b.y1; }

TEST(Detector, YuNetFindsTheAnnotatedFace) {
    FACETRACK_REQUIRE_SHARED();
    DetectorConfig config;
    config.kind = DetectorKind::YuNet;
    auto detector = createFaceDetector(config);
    EXPECT_EQ(detector->kind(), "yunet");
    const auto face = sampleFace();
    const auto found = detector->detect(core::viewOf(face.image));
    ASSERT_GE(found.size(), 1u);
    EXPECT_TRUE(boxContains(found[0].box, face.points.rowwise().mean()));
    EXPECT_GT(found[0].score, 0.8f);
    for (std::size_t i = 1; i < found.size(); ++i) EXPECT_LE(found[i].score, found[i - 1].score);
}

TEST(Detector, BoxesMapBackFromTheDownscaledFrame) {
    FACETRACK_REQUIRE_SHARED();
    auto detector = createFaceDetector(configOf(DetectorKind::YuNet));
    const auto face = sampleFace();
    cv::Mat canvas(480, 640, CV_8UC3, cv::Scalar(40, 40, 40));  // 640 px wide: detected at 320
    cv::Mat scaled;
    cv::resize(face.image, scaled, {}, 1.5, 1.5);
    scaled.copyTo(canvas(cv::Rect(200, 50, scaled.cols, scaled.rows)));
    const auto small = detector->detect(core::viewOf(face.image));
    const auto big = detector->detect(core::viewOf(canvas));
    ASSERT_FALSE(small.empty());
    ASSERT_FALSE(big.empty());
    // Same face: the box moves by the offset and grows by 1.5, within a few pixels.
    EXPECT_NEAR(big[0].box.x0, 200.f + 1.5f * small[0].box.x0, 8.f);
    EXPECT_NEAR(big[0].box.y0, 50.f + 1.5f * small[0].box.y0, 8.f);
    EXPECT_NEAR(big[0].box.width(), 1.5f * small[0].box.width(), 10.f);
}

TEST(Detector, CascadeFindsTheAnnotatedFace) {
    FACETRACK_REQUIRE_SHARED();
    auto detector = createFaceDetector(configOf(DetectorKind::Cascade));
    EXPECT_EQ(detector->kind(), "cascade");
    const auto face = sampleFace();
    const auto found = detector->detect(core::viewOf(face.image));
    ASSERT_GE(found.size(), 1u);
    EXPECT_TRUE(boxContains(found[0].box, face.points.rowwise().mean()));
    EXPECT_GT(found[0].score, 0.f);
    EXPECT_LE(found[0].score, 1.f);
}

TEST(Detector, FallsBackToTheCascadeWithoutYuNetAndSaysSo) {
    const fs::path empty = fs::path(test::tempPath("empty"));
    fs::create_directories(empty);
    ScopedEnv shared("FACETRACK_SHARED_DIR", empty.string());
    ScopedEnv models("FACETRACK_MODEL_DIR", empty.string());
    ::unsetenv("FACETRACK_YUNET_MODEL");
    EXPECT_EQ(findYuNetModel(), "");
    std::vector<std::string> log;
    setLogHandler([&](const std::string& line) { log.push_back(line); });
    auto detector = createFaceDetector();
    setLogHandler(nullptr);
    EXPECT_EQ(detector->kind(), "cascade");
    ASSERT_EQ(log.size(), 1u);
    EXPECT_NE(log[0].find("falling back"), std::string::npos) << log[0];
    EXPECT_THROW(createFaceDetector(configOf(DetectorKind::YuNet)), Error);
}

TEST(Detector, ExplicitMissingModelIsAnErrorNotAFallback) {
    DetectorConfig config;
    config.yunet_model = "/nonexistent/yunet.onnx";
    try {
        createFaceDetector(config);
        FAIL() << "no error for a missing model";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("/nonexistent/yunet.onnx"), std::string::npos) << e.what();
    }
    ScopedEnv env("FACETRACK_YUNET_MODEL", "/nonexistent/env.onnx");
    EXPECT_THROW(createFaceDetector(), Error);
}

TEST(Detector, ACorruptModelFileIsAnError) {
    const std::string path = test::tempPath("bad.onnx");
    std::ofstream(path) << "not an onnx model";
    DetectorConfig config;
    config.yunet_model = path;
    EXPECT_THROW(createFaceDetector(config), Error);
    fs::remove(path);
}

TEST(Detector, NoFaceInBlankNoiseOrTinyFrames) {
    for (auto kind : {DetectorKind::Auto, DetectorKind::Cascade}) {
        auto detector = createFaceDetector(configOf(kind));
        cv::Mat noise(480, 640, CV_8UC3);
        cv::randu(noise, 0, 255);
        EXPECT_TRUE(detector->detect(core::viewOf(cv::Mat::zeros(480, 640, CV_8UC3))).empty());
        EXPECT_TRUE(detector->detect(core::viewOf(noise)).empty());
        EXPECT_TRUE(detector->detect(core::viewOf(cv::Mat::zeros(1, 1, CV_8UC1))).empty());
        EXPECT_TRUE(detector->detect(core::viewOf(cv::Mat::zeros(3000, 2, CV_8UC3))).empty());
        EXPECT_THROW(detector->detect(ImageView{}), Error);
    }
}

}  // namespace
}  // namespace facetrack
