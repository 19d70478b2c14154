#include "facetrack/arkit.hpp"
#include "facetrack/error.hpp"
#include "facetrack/face_model.hpp"
#include "model/face_model_data.hpp"
#include "model/internals.hpp"
#include "test_support.hpp"

#include <set>

namespace facetrack {
namespace {

TEST(Arkit, FiftyTwoUniqueNamesInFixedOrder) {
    const auto& names = arkitNames();
    EXPECT_EQ(std::set<std::string_view>(names.begin(), names.end()).size(), 52u);
    EXPECT_EQ(names.front(), "eyeBlinkLeft");
    EXPECT_EQ(names[17], "jawOpen");
    EXPECT_EQ(names.back(), "tongueOut");
    for (int i = 0; i < kArkitBlendshapeCount; ++i) EXPECT_EQ(arkitIndex(names[i]), i);
    EXPECT_EQ(arkitIndex("eyeBlink_L"), -1);
}

class ArkitMappingTest : public ::testing::Test {
protected:
    std::shared_ptr<const FaceModel> model = FaceModel::load(test::shippedFaceModel());
    std::vector<float> oneHot(const std::string& name) const {
        const auto& names = model->expressionNames();
        std::vector<float> w(names.size(), 0.f);
        w.at(std::find(names.begin(), names.end(), name) - names.begin()) = 1.f;
        return w;
    }
};

TEST_F(ArkitMappingTest, OneToOneShapesMapByName) {
    const auto arkit = model->toArkit(oneHot("jawOpen"));
    for (int i = 0; i < kArkitBlendshapeCount; ++i) {
        EXPECT_EQ(arkit[i], i == arkitIndex("jawOpen") ? 1.f : 0.f) << arkitNames()[i];
    }
    EXPECT_EQ(model->toArkit(oneHot("eyeBlink_L"))[arkitIndex("eyeBlinkLeft")], 1.f);
    EXPECT_EQ(model->toArkit(oneHot("mouthLeft"))[arkitIndex("mouthLeft")], 1.f);
    EXPECT_EQ(model->toArkit(oneHot("jawRight"))[arkitIndex("jawRight")], 1.f);
}

TEST_F(ArkitMappingTest, PairsAreAveragedAndTongueOutIsZero) {
    EXPECT_EQ(model->toArkit(oneHot("browInnerUp_L"))[arkitIndex("browInnerUp")], 0.5f);
    EXPECT_EQ(model->toArkit(oneHot("cheekPuff_R"))[arkitIndex("cheekPuff")], 0.5f);
    std::vector<float> all(model->expressionNames().size(), 1.f);
    const auto arkit = model->toArkit(all);
    EXPECT_EQ(arkit[arkitIndex("tongueOut")], 0.f);
    for (int i = 0; i < kArkitBlendshapeCount - 1; ++i) EXPECT_EQ(arkit[i], 1.f) << arkitNames()[i];
}

TEST_F(ArkitMappingTest, LeftIsTheSubjectsLeft) {
    // ARKit's "Left" is the subject's left; in the model that is +x.
    const auto& e = model::dataOf(*model).expressions;
    const auto blinkLeft = std::find_if(e.begin(), e.end(), [](const auto& s) { return s.name == "eyeBlink_L"; });
    ASSERT_NE(blinkLeft, e.end());
    float weightedX = 0.f;
    for (std::size_t k = 0; k < blinkLeft->vertices.size(); ++k) {
        weightedX += model::dataOf(*model).neutral(0, blinkLeft->vertices[k]) * blinkLeft->deltas.col(k).norm();
    }
    EXPECT_GT(weightedX, 0.f);
}

TEST_F(ArkitMappingTest, WrongWeightCountIsAnError) { EXPECT_THROW(model->toArkit({0.f, 1.f}), Error); }

}  // namespace
}  // namespace facetrack
