#pragma once
// The MediaPipe teacher labels of ../shared/data/teacher (its README): iris
// centre and contour and eyelid points per eye, for every 300-W crop and clip
// frame. Another model's predictions, not ground truth.

#include "gaze/eye_patch.hpp"

#include "facetrack/geometry.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace facetrack::tools {

struct TeacherEye {
    Point2 iris_centre;
    std::array<Point2, 4> iris_contour;  ///< nasal, upper, temporal, lower
    std::array<Point2, 7> upper_lid;     ///< temporal -> nasal, corners excluded
    std::array<Point2, 9> lower_lid;     ///< outer corner (0) -> inner corner (8)
    bool in_pts_eye = true;              ///< 300-W only: the iris centre is inside the annotated eye

    float irisRadius() const;
    /// Lid aperture over eye width: the gap between the lids, perpendicular to
    /// the corner axis, averaged at 35, 50 and 65 % of the way from the outer
    /// corner, over the corner distance.
    float aperture() const;
};

struct TeacherRecord {
    TeacherEye left, right;  ///< the subject's
    const TeacherEye& eye(gaze::Eye e) const { return e == gaze::Eye::Left ? left : right; }
};

/// Records keyed by "IMAGE" (300-W path relative to faces300w) or "CLIP#FRAME";
/// lines without a face are left out. Throws Error when the file cannot be read.
std::map<std::string, TeacherRecord> readTeacher(const std::string& jsonlPath);
std::string teacherKey(const std::string& clip, int frame);

/// The teacher's lids and iris in patch coordinates, and the class of a patch pixel.
struct PatchLabels {
    std::vector<Point2> upper, lower;  ///< polylines sorted by x, corners included
    Point2 iris_centre;
    float iris_radius = 0.f;
    float aperture = 0.f;
    /// gaze::kSkin, kSclera or kIris.
    int pixelClass(float x, float y) const;
};
PatchLabels patchLabels(const TeacherEye& eye, const gaze::EyePatch& patch);

}  // namespace facetrack::tools
