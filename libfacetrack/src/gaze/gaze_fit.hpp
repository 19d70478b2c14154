#pragma once
// The MAP estimate of both eyes' gaze (Wang, Shi, Xia, Chai 2016, sec. 5).
//
// Eyeball model, per eye, in the head (model) frame: a rotation centre c; the
// iris a disc of radius r_i = kIrisRadiusMm whose centre sits d_i =
// kIrisDistanceMm in front of c along the gaze direction
//   g(theta, phi) = (sin theta cos phi, sin phi, cos theta cos phi),
// theta (yaw) > 0 towards the subject's left (+x), phi (pitch) > 0 up.
//
// Data term, per eye: the disc projected through the head pose and camera
// into the eye patch gives a soft iris indicator D(q) (1 inside the projected
// ellipse, falling to 0 over about a patch pixel at its edge); the lids
// occlude it where the pixel classifier sees no eye opening, so the model of
// the visible iris is D(q) P_open(q), compared with the classifier's P_iris(q):
//   E_data = w sum_q (P_iris(q) - D(q) P_open(q))^2 / sigma_d^2,
// w the eye's openness weight (0 for a closed eye: no data).
// Appearance term, per eye: the normalised patch I at every pixel p of a window
// about the iris, against the visible eye in two tones, the iris a constant mu
// inside the disc and the sclera a plane outside it,
//   m(p) = mu D(p) + (1 - D(p)) (a + b x + c y),
//   E_pixels = w sum_p P_open(p)^2 (I(p) - m(p))^2 / sigma_a^2,
// with (mu, a, b, c) the weighted least-squares fit for the disc being tried:
// the iris is where the patch is darker in the shape the eyeball model
// predicts, whatever the classifier's map leans towards.
// Priors: a binocular one (a shared fixation point: equal pitch, vergence
// theta_R - theta_L near v0), a temporal one (theta_t - theta_{t-1}) and a weak
// pull to straight ahead. A few Gauss-Newton steps (analytic Jacobian) from an
// initial guess by back-projecting the iris probability's centroid onto the eyeball.

#include "core/camera.hpp"
#include "gaze/eye_patch.hpp"

#include "facetrack/face_model.hpp"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <array>

namespace facetrack::gaze {

/// Human iris diameter ~11.7 mm; the iris plane ~10 mm in front of the eye's
/// rotation centre (rotation centre ~13.5 mm behind the cornea apex, anterior
/// chamber ~3.5 mm deep).
constexpr float kIrisRadiusMm = 5.85f;
constexpr float kIrisDistanceMm = 10.0f;

Eigen::Vector3f gazeDirection(float yaw, float pitch);

/// The eyeball's rotation centre for this model: the face model's eyeball
/// (centre `meshCentre` on a mesh, radius R, iris radius r) keeps its iris
/// plane where the mesh has it, sqrt(R^2 - r^2) in front of its centre along
/// the optical axis, and the centre moves to kIrisDistanceMm behind that plane.
Eigen::Vector3f rotationCentre(const EyeballGeometry& eye, const Vec3& meshCentre);
/// The radius of the sphere the iris disc lies on: sqrt(d_i^2 + r_i^2).
float eyeballRadiusMm();

/// One eye as the fit sees it.
struct EyeObservation {
    const EyePatch* patch = nullptr;
    const cv::Mat* iris = nullptr;  ///< P(iris) on kClassifiedRegion's grid (rows() x columns(), CV_32F)
    const cv::Mat* open = nullptr;  ///< P(sclera) + P(iris), same size
    float weight = 0.f;             ///< 0 closed .. 1 open
    Eigen::Vector3f centre;         ///< eyeball rotation centre, camera frame, mm
};

struct GazeFitSettings {
    float data_sigma = 0.3f;         ///< per-pixel probability noise
    float pixel_sigma = 1.f;         ///< per-pixel intensity noise (normalised patch); 0: no appearance term
    float temporal_sigma_deg = 8.f;  ///< per frame
    float pitch_sigma_deg = 2.f;     ///< the two eyes' pitch difference
    float vergence_deg = 3.f;        ///< theta_R - theta_L for a typical screen distance
    float vergence_sigma_deg = 4.f;
    float ahead_sigma_deg = 40.f;
    /// Gauss-Newton steps at most; the fit stops earlier once no angle moves by
    /// converged_step_deg. Four steps left a single frame's fit short of its
    /// minimum on eyes looking far up (docs/gaze.md).
    int iterations = 8;
    float converged_step_deg = 0.1f;
};

/// Both eyes' (yaw, pitch) in radians, [0] the subject's left eye, [1] the right.
using GazeAngles = std::array<Eigen::Vector2f, 2>;

/// The projected iris of `eye` at (yaw, pitch), in patch pixels: centre and
/// two conjugate semi-axes. False when it is behind the camera.
struct ProjectedIris {
    Eigen::Vector2f centre, axis1, axis2;
};
bool projectIris(const EyeObservation& eye, const Eigen::Matrix3f& cameraFromHead, const core::Camera& camera,
                 const Eigen::Vector2f& angles, ProjectedIris& out);
/// The iris centre at (yaw, pitch) in frame pixels.
Eigen::Vector2f irisCentreInImage(const Eigen::Vector3f& centre, const Eigen::Matrix3f& cameraFromHead, const core::Camera& camera,
                                  const Eigen::Vector2f& angles);

/// The MAP estimate, from `previous` (used by the temporal prior when
/// `havePrevious`, and as the start for an eye without a usable centroid).
GazeAngles fitGaze(const std::array<EyeObservation, 2>& eyes, const Eigen::Matrix3f& cameraFromHead, const core::Camera& camera,
                   const GazeAngles& previous, bool havePrevious, const GazeFitSettings& settings = {});

}  // namespace facetrack::gaze
