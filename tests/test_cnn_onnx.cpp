// The CNN export path (tools/train_cnn, docs/cnn.md): a net exported by train_stage.py's export()
// loads in OpenCV's dnn and gives torch's outputs (fixture: tools/train_cnn/make_parity_fixture.py);
// the cascade's file format; the landmark net's geometry; the cnn stage wired into the Tracker.

#include "cnn/cnn_model_data.hpp"
#include "cnn/landmark_net.hpp"
#include "cnn/update_net.hpp"
#include "facetrack/error.hpp"
#include "facetrack/face_model.hpp"
#include "fit/face_fitter.hpp"
#include "facetrack/tracker.hpp"
#include "test_support.hpp"

#include <opencv2/dnn.hpp>

#include <cmath>
#include <fstream>
#include <iterator>

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

/// A cascade of the parity fixture's net (random weights; 6 pose + 1 expression outputs): for
/// the file format and the wiring, not for accuracy.
cnn::CnnModelData parityCascade() {
    cnn::CnnModelData m;
    m.expressions = {"jawOpen"};
    m.stages.push_back({2, test::fixtureBytes("cnn_parity.onnx")});
    m.provenance = "the export parity fixture";
    return m;
}

TEST(CnnModelFile, RoundTripsAndRejectsDamageAndWrongNets) {
    const cnn::CnnModelData m = parityCascade();
    const std::string path = test::tempPath("cascade.ftm");
    cnn::writeCnnModel(path, m);
    const auto loaded = CnnModel::load(path);
    EXPECT_EQ(loaded->data().expressions, m.expressions);
    ASSERT_EQ(loaded->rounds(), std::vector<int>{2});
    EXPECT_EQ(loaded->data().stages[0].onnx, m.stages[0].onnx);
    EXPECT_EQ(loaded->provenance(), m.provenance);
    EXPECT_FALSE(loaded->hasLandmarkNet());
    EXPECT_FALSE(loaded->expressionsOnly());
    cnn::CnnModelData reading = m;
    reading.expressions_only = true;
    cnn::writeCnnModel(test::tempPath("cascade_expressions.ftm"), reading);
    EXPECT_TRUE(CnnModel::load(test::tempPath("cascade_expressions.ftm"))->expressionsOnly());
    for (const auto& [neutral, reported] : {std::pair<std::vector<float>, std::vector<bool>>{{0.1f, 0.2f}, {}}, {{}, {true, false}},
                                            {{1.f}, {}}, {{std::nanf("")}, {}}}) {
        cnn::CnnModelData bad = reading;  // one expression: two values, or a neutral outside [0, 1)
        bad.neutral = neutral;
        bad.reported = reported;
        EXPECT_THROW(cnn::writeCnnModel(test::tempPath("cascade_bad.ftm"), bad), Error);
    }
    cnn::CnnModelData withLandmarks = m;
    withLandmarks.landmark_net = test::fixtureBytes("cnn_landmarks_fixture.onnx");
    cnn::writeCnnModel(test::tempPath("cascade_landmarks.ftm"), withLandmarks);
    const auto reloaded = CnnModel::load(test::tempPath("cascade_landmarks.ftm"));
    EXPECT_TRUE(reloaded->hasLandmarkNet());
    EXPECT_EQ(reloaded->data().landmark_net, withLandmarks.landmark_net);
    EXPECT_THROW(cnn::PatchNet(withLandmarks.landmark_net, 64, 6 + 1, "landmark net"), Error);
    {
        std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(200);
        f.put('\x55');
    }
    try {
        CnnModel::load(path);
        ADD_FAILURE() << "a damaged cascade loaded";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
    EXPECT_THROW(CnnModel::load(test::tempPath("no_such_cascade.ftm")), Error);
    // A net of another output count, or not a net, is refused with its name.
    try {
        cnn::PatchNet(m.stages[0].onnx, 64, 6 + 2, "stage 1");
        ADD_FAILURE() << "a 7-output net passed for 6 + 2";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("stage 1 gives 7 outputs"), std::string::npos) << e.what();
    }
    EXPECT_THROW(cnn::PatchNet("not an onnx file", 64, 6 + 1, "stage 1"), Error);
    cnn::CnnModelData none = m;
    none.stages.clear();
    EXPECT_THROW(cnn::writeCnnModel(test::tempPath("empty.ftm"), none), Error);
}

TEST(CnnLandmarks, DisplacementsAreInPatchPixelsWhateverTheFacesPlaceSizeAndRoll) {
    const auto face = FaceModel::load(test::shippedFaceModel());
    const cnn::WarpLayout layout = cnn::makeWarpLayout(face->data(), {});
    const fit::Camera camera = fit::cameraFor(640, 480, 60.0, 0.0);
    fit::FaceParams params;
    // The face centre (WarpLayout::centre, ahead of the model origin) at 60 cm, then at 30 cm.
    params.pose.tail<3>() = Eigen::Vector3d(2.0, -1.0, 60.0) - layout.centre;
    const Eigen::Matrix2d far = cnn::patchToFrame(layout, cnn::projectAnchors(layout, Eigen::VectorXd(), camera, params));
    params.pose.tail<3>() = Eigen::Vector3d(1.0, -0.5, 30.0) - layout.centre;
    const Eigen::Matrix2d near = cnn::patchToFrame(layout, cnn::projectAnchors(layout, Eigen::VectorXd(), camera, params));
    EXPECT_NEAR(near.determinant() / far.determinant(), 4.0, 0.2);  // twice the size: four times the area
    EXPECT_NEAR(far(0, 1), 0.0, 0.02 * far(0, 0));  // upright: no shear or turn
    params.pose.head<3>() = fit::omegaFromEuler(Eigen::Vector3d(0.0, 0.0, 30.0));
    const Eigen::Matrix2d rolled = cnn::patchToFrame(layout, cnn::projectAnchors(layout, Eigen::VectorXd(), camera, params));
    EXPECT_NEAR(std::abs(std::atan2(rolled(1, 0), rolled(0, 0))) * 180.0 / M_PI, 30.0, 1.0);
    EXPECT_NEAR(rolled.determinant(), near.determinant(), 0.05 * near.determinant());
    // Out and back.
    fit::Landmarks2d p = fit::Landmarks2d::Random() * 100.0;
    Eigen::VectorXd d = Eigen::VectorXd::Random(cnn::kLandmarkOutputs) * 5.0;
    EXPECT_LT((cnn::displacementsOf(rolled, p, cnn::displaced(rolled, p, d)) - d).cwiseAbs().maxCoeff(), 1e-9);
    // A displacement along the patch's x moves a point along the face's rolled x axis.
    d.setZero();
    d[0] = 1.0;
    const Eigen::Vector2d moved = cnn::displaced(rolled, p, d).col(0) - p.col(0);
    EXPECT_NEAR(std::abs(std::atan2(moved.y(), moved.x())) * 180.0 / M_PI, 30.0, 1.0);
}

TEST(CnnRefine, StopsWhenTheFaceIsNotInFrontOfTheCamera) {
    const auto face = FaceModel::load(test::shippedFaceModel());
    const auto& names = face->expressionNames();
    const int jawOpen = static_cast<int>(std::find(names.begin(), names.end(), "jawOpen") - names.begin());
    const cnn::WarpLayout layout = cnn::makeWarpLayout(face->data(), {jawOpen});
    cnn::PatchNet net(parityCascade().stages[0].onnx, 64, 6 + 1, "parity");
    cnn::RefineWork work;
    work.identity_shape = fit::shapeWithIdentity(layout.anchors, Eigen::VectorXd());
    const cv::Mat grey(480, 640, CV_8UC1, cv::Scalar(90));
    const fit::Camera camera = fit::cameraFor(640, 480, 60.0, 0.0);
    fit::FaceParams params;
    params.expression = Eigen::VectorXd::Zero(1);
    params.pose[5] = 50.0;
    EXPECT_TRUE(cnn::refine(layout, net, grey, camera, params, 2, work));
    EXPECT_TRUE(params.pose.allFinite());
    params.pose.tail<3>() << 0.0, 0.0, -40.0;  // behind the camera
    EXPECT_FALSE(cnn::refine(layout, net, grey, camera, params, 2, work));
    params.pose[0] = std::nan("");
    EXPECT_FALSE(cnn::refine(layout, net, grey, camera, params, 1, work));
}

/// The shipped models without eyes or a cascade, and a tracker without the filter: the cnn stage's inputs alone.
Models fitOnly() {
    Models models = Models::loadDefault();
    models.eyes = nullptr;
    models.cnn = nullptr;
    return models;
}

TrackerConfig unfiltered() {
    TrackerConfig config;
    config.filter.enabled = false;
    return config;
}

TEST(CnnStage, RefinesTheFitsPoseAndExpressionsInTheTracker) {
    FACETRACK_REQUIRE_SHARED();
    const std::string path = test::tempPath("cascade_stage.ftm");
    cnn::writeCnnModel(path, parityCascade());
    Models models = fitOnly();
    const TrackerConfig config = unfiltered();
    Tracker without(models, config);
    models.cnn = CnnModel::load(path);
    Tracker with(models, config);
    const auto stages = with.stages();
    const auto cnnStage = std::find_if(stages.begin(), stages.end(), [](const StageInfo& s) { return s.name == "cnn"; });
    ASSERT_NE(cnnStage, stages.end());
    EXPECT_TRUE(cnnStage->available) << cnnStage->detail;
    EXPECT_NE(cnnStage->detail.find("2 rounds"), std::string::npos) << cnnStage->detail;
    const auto names = with.estimatedShapes();
    EXPECT_NE(std::find(names.begin(), names.end(), "jawOpen"), names.end());

    const auto frames = test::clipFrames(10);
    FrameResult a, b;
    int differ = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
        const ImageView view{frames[i].data, frames[i].cols, frames[i].rows, frames[i].step, PixelFormat::Bgr8};
        without.process(view, 0.04 * static_cast<double>(i), a);
        with.process(view, 0.04 * static_cast<double>(i), b);
        ASSERT_EQ(a.faces.size(), b.faces.size()) << "frame " << i;
        if (b.faces.empty()) continue;
        const HeadPose& pa = *a.faces[0].pose;
        const HeadPose& pb = *b.faces[0].pose;
        for (const float v : {pb.rotation.w, pb.rotation.x, pb.rotation.y, pb.rotation.z, pb.translation_mm.z}) EXPECT_TRUE(std::isfinite(v));
        // The landmarks are the LBF's; the pose (random net's updates) is the cascade's.
        EXPECT_EQ((*a.faces[0].landmarks)[30].x, (*b.faces[0].landmarks)[30].x);
        differ += std::abs(pa.euler_deg.y - pb.euler_deg.y) > 0.01f || std::abs(pa.translation_mm.z - pb.translation_mm.z) > 0.01f;
    }
    EXPECT_GE(differ, 5);
    const auto timing = std::find_if(b.timings.begin(), b.timings.end(), [](const StageTiming& t) { return t.stage == "cnn"; });
    EXPECT_NE(timing, b.timings.end());
}

// A cascade that reads expressions keeps the fit's pose and the shapes the fit estimates, and adds
// the others. The fixture net's update is constant: no pose change, +0.3 on its one expression,
// named as a shape the fit does not estimate (browDown_L: it reads 0.3; with a neutral of 0.1,
// (0.3 - 0.1) / 0.9; not reported: 0), or as one it does (jawOpen: the stage writes nothing).
TEST(CnnStage, AnExpressionsOnlyCascadeKeepsTheFitsPoseAndShapes) {
    FACETRACK_REQUIRE_SHARED();
    Models models = fitOnly();
    const TrackerConfig config = unfiltered();
    Tracker without(models, config);
    const auto fitted = without.estimatedShapes();
    ASSERT_EQ(std::find(fitted.begin(), fitted.end(), "browDownLeft"), fitted.end());
    ASSERT_NE(std::find(fitted.begin(), fitted.end(), "jawOpen"), fitted.end());
    const auto frames = test::clipFrames(6);
    struct Case {
        std::string shape;
        std::vector<float> neutral;
        std::vector<bool> reported;
        float browDownLeft;  ///< what the stage reports; negative: the fit's own value
    };
    for (const Case& c : {Case{"browDown_L", {}, {}, 0.3f}, Case{"browDown_L", {0.1f}, {}, 0.2f / 0.9f},
                          Case{"browDown_L", {}, {false}, -1.f}, Case{"jawOpen", {}, {}, -1.f}}) {
        cnn::CnnModelData m;
        m.expressions = {c.shape};
        m.stages.push_back({1, test::fixtureBytes("cnn_expression_fixture.onnx")});
        m.expressions_only = true;
        m.neutral = c.neutral;
        m.reported = c.reported;
        const std::string path = test::tempPath("cascade_reads_" + c.shape + ".ftm");
        cnn::writeCnnModel(path, m);
        models.cnn = CnnModel::load(path);
        EXPECT_EQ(models.cnn->data().neutral, c.neutral);
        EXPECT_EQ(models.cnn->data().reported, c.reported);
        Tracker with(models, config);
        without.reset();
        EXPECT_EQ(with.estimatedShapes().size(), fitted.size() + (c.browDownLeft < 0.f ? 0 : 1)) << c.shape;
        FrameResult a, b;
        for (std::size_t i = 0; i < frames.size(); ++i) {
            const ImageView view{frames[i].data, frames[i].cols, frames[i].rows, frames[i].step, PixelFormat::Bgr8};
            without.process(view, 0.04 * static_cast<double>(i), a);
            with.process(view, 0.04 * static_cast<double>(i), b);
            ASSERT_EQ(a.faces.size(), 1u);
            ASSERT_EQ(b.faces.size(), 1u);
            EXPECT_EQ(a.faces[0].pose->rotation.x, b.faces[0].pose->rotation.x) << c.shape << " frame " << i;
            EXPECT_EQ(a.faces[0].pose->translation_mm.z, b.faces[0].pose->translation_mm.z) << c.shape << " frame " << i;
            const auto& wa = a.faces[0].expression->arkit;
            const auto& wb = b.faces[0].expression->arkit;
            for (std::size_t k = 0; k < wa.size(); ++k) {
                const bool read = arkitNames()[k] == "browDownLeft" && c.browDownLeft >= 0.f;
                EXPECT_NEAR(wb[k], read ? c.browDownLeft : wa[k], read ? 1e-5f : 0.f) << arkitNames()[k] << ", reading " << c.shape << ", frame " << i;
            }
        }
    }
}

TEST(CnnStage, TheLandmarkNetMovesTheRefinedFacesProjectedLandmarks) {
    FACETRACK_REQUIRE_SHARED();
    // The fixture's net displaces every point by (+3, 0) patch pixels: the stage's landmarks must be
    // the projection of its own refined face, each moved by L (3, 0).
    cnn::CnnModelData m = parityCascade();
    m.landmark_net = test::fixtureBytes("cnn_landmarks_fixture.onnx");
    const std::string path = test::tempPath("cascade_landmark_stage.ftm");
    cnn::writeCnnModel(path, m);
    Models models = Models::loadDefault();
    models.eyes = nullptr;
    models.cnn = CnnModel::load(path);
    TrackerConfig config;
    config.filter.enabled = false;
    Tracker tracker(models, config);
    const auto stages = tracker.stages();
    const auto cnnStage = std::find_if(stages.begin(), stages.end(), [](const StageInfo& s) { return s.name == "cnn"; });
    ASSERT_NE(cnnStage, stages.end());
    EXPECT_NE(cnnStage->detail.find("landmark net"), std::string::npos) << cnnStage->detail;

    const auto& names = models.face->expressionNames();
    const int jawOpen = static_cast<int>(std::find(names.begin(), names.end(), "jawOpen") - names.begin());
    const cnn::WarpLayout layout = cnn::makeWarpLayout(models.face->data(), {jawOpen});
    const fit::FitBasis basis = cnn::landmarkBasis(*models.face, {jawOpen});
    const auto frames = test::clipFrames(6);
    FrameResult out;
    int checked = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
        const ImageView view{frames[i].data, frames[i].cols, frames[i].rows, frames[i].step, PixelFormat::Bgr8};
        tracker.process(view, 0.04 * static_cast<double>(i), out);
        if (out.faces.empty()) continue;
        const FaceResult& r = out.faces[0];
        ASSERT_TRUE(r.landmarks && r.pose && r.expression);
        fit::FaceParams params;
        fit::poseParamsOf(*r.pose, params);
        params.expression = Eigen::VectorXd::Constant(1, r.expression->native[static_cast<std::size_t>(jawOpen)]);
        Eigen::VectorXd identity = Eigen::VectorXd::Zero(basis.identityCount());
        for (std::size_t k = 0; k < r.identity.size(); ++k) identity[static_cast<Eigen::Index>(k)] = r.identity[k];
        const fit::Camera camera = fit::cameraFor(view.width, view.height, 60.0, 0.0);
        const Eigen::Matrix2d toFrame = cnn::patchToFrame(layout, cnn::projectAnchors(layout, identity, camera, params));
        Eigen::Matrix3Xd slots;
        const fit::Landmarks2d projected = cnn::projectedLandmarks(basis, fit::shapeWithIdentity(basis, identity), camera, params, slots);
        const Eigen::Vector2d shift = toFrame * Eigen::Vector2d(3.0, 0.0);
        EXPECT_GT(shift.x(), 3.0);  // a patch pixel is more than a frame pixel on this clip's face
        double worst = 0.0;
        for (int k = 0; k < 68; ++k) {
            const Eigen::Vector2d got((*r.landmarks)[static_cast<std::size_t>(k)].x, (*r.landmarks)[static_cast<std::size_t>(k)].y);
            worst = std::max(worst, (got - projected.col(k) - shift).norm());
        }
        EXPECT_LT(worst, 0.1) << "frame " << i;  // the public pose is rounded to floats
        EXPECT_LE(r.box.x0, (*r.landmarks)[0].x);
        ++checked;
    }
    EXPECT_GE(checked, 4);
}

}  // namespace
}  // namespace facetrack
