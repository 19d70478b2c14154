#pragma once
// A software rasteriser that renders the face model with eyes of known gaze,
// for the gaze stage's synthetic evaluation and tests (docs/gaze.md). The skin
// is the model's face mesh, z-buffered and shaded (Lambert, one light, smooth
// normals); each eye is the gaze stage's own eyeball model (gaze_fit.hpp), a
// sphere ray-traced per pixel behind the lids: sclera, a textured iris with a
// dark limbal ring, a pupil. The lids come from the mesh, so the model's
// eyeBlink and eyeLook shapes close and move them.

#include "facetrack/face_model.hpp"
#include "facetrack/result.hpp"

#include <opencv2/core.hpp>

#include <array>
#include <memory>
#include <random>
#include <vector>

namespace facetrack::tools {

struct SyntheticFace {
    Quaternion rotation;  ///< camera from model (result.hpp's HeadPose convention)
    Vec3 translation_mm{0, 0, 600};
    std::vector<float> expression;  ///< native weights (empty: neutral)
    /// (yaw, pitch) in degrees per eye, head frame, as EyeGaze: [0] the subject's left, [1] right.
    std::array<std::array<float, 2>, 2> gaze_deg{};
    float fx = 600.f, fy = 600.f, cx = 320.f, cy = 240.f;
    int width = 640, height = 480;
    float noise_sigma = 2.f;                         ///< grey levels, Gaussian
    float blur_sigma = 0.f;                          ///< pixels
    float skin = 1.f;                                ///< skin albedo (1: a light skin)
    float iris = 1.f;                                ///< iris albedo (1: a mid brown; below 1 darker, above lighter)
    float lash = 1.f;                                ///< lash line darkness and width
    std::array<float, 3> light{-0.3f, -0.4f, -1.f};  ///< towards the light, camera frame
    unsigned seed = 1;
};

/// Per pixel of a render: what it shows (gaze::PixelClass values: skin 0, sclera 1, iris 2).
using ClassMap = cv::Mat;  // CV_8U

class SyntheticRenderer {
public:
    /// `markings`: brows and lips painted on the skin (false: the bare
    /// mannequin, on which the landmarks place the brows by guesswork).
    explicit SyntheticRenderer(std::shared_ptr<const FaceModel> model, bool markings = true);
    /// BGR, width x height; `classes`, when given, gets each pixel's class.
    cv::Mat render(const SyntheticFace& face, ClassMap* classes = nullptr) const;
    /// The true gaze direction of eye e (0 left, 1 right) in the camera frame.
    Vec3 gazeInCamera(const SyntheticFace& face, int e) const;
    /// The 68 landmarks' projections, in the model's landmark convention
    /// (FaceModel::landmarkPoints: where a 300-W annotator would put them).
    Landmarks68 landmarks(const SyntheticFace& face) const;
    /// A face detector's box for the render: the landmarks' bounding box with
    /// 10 % margins, 20 % above (a detector's box includes the forehead).
    Box faceBox(const SyntheticFace& face) const;
    /// The distance between the eyeball centres in pixels (the inter-ocular distance).
    float interocularPx(const SyntheticFace& face) const;

private:
    std::shared_ptr<const FaceModel> model_;
    std::vector<std::array<int, 3>> skin_;  // face-skin triangles
    std::vector<int> landmark_vertices_;
    std::vector<std::array<float, 3>> neutral_front_;  // per face vertex: (x, y) on the neutral face, 1 on its front (0 the sides)
    std::shared_ptr<const class FaceMarkings> markings_;
};

}  // namespace facetrack::tools
