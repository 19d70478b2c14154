// The CNN export path (tools/train_cnn, docs/cnn.md): a net exported by train_stage.py's export()
// loads in OpenCV's dnn and gives torch's outputs. Fixture: tools/train_cnn/make_parity_fixture.py.

#include "test_support.hpp"

#include <opencv2/dnn.hpp>

#include <fstream>

namespace facetrack {
namespace {

std::vector<float> readFloats(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    EXPECT_TRUE(in) << path;
    std::vector<float> v(static_cast<std::size_t>(in.tellg()) / sizeof(float));
    in.seekg(0);
    in.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(float)));
    return v;
}

TEST(CnnExport, OpenCvDnnMatchesTorchOnStoredInputs) {
    const std::string dir = test::sourceDir() + "/tests/data/";
    cv::dnn::Net net = cv::dnn::readNetFromONNX(dir + "cnn_parity.onnx");
    ASSERT_FALSE(net.empty());
    const std::vector<float> input = readFloats(dir + "cnn_parity_input.f32");
    const std::vector<float> expected = readFloats(dir + "cnn_parity_output.f32");
    ASSERT_EQ(input.size(), 3u * 64 * 64);
    ASSERT_EQ(expected.size() % 3, 0u);
    const int sizes[] = {3, 1, 64, 64};
    const cv::Mat blob(4, sizes, CV_32F, const_cast<float*>(input.data()));
    net.setInput(blob);
    const cv::Mat out = net.forward();
    ASSERT_EQ(out.total(), expected.size());
    double worst = 0.0;
    for (std::size_t i = 0; i < expected.size(); ++i) worst = std::max(worst, std::abs(double(out.ptr<float>()[i]) - expected[i]));
    EXPECT_LT(worst, 1e-4);
}

}  // namespace
}  // namespace facetrack
