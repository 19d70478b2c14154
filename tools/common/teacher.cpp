#include "common/teacher.hpp"

#include "gaze/eye_model_data.hpp"

#include "facetrack/error.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>

namespace facetrack::tools {

namespace {
Point2 point(const nlohmann::json& j) { return {j.at(0).get<float>(), j.at(1).get<float>()}; }

template <std::size_t N>
std::array<Point2, N> points(const nlohmann::json& j) {
    std::array<Point2, N> out;
    if (j.size() != N) throw Error("teacher record: expected " + std::to_string(N) + " points");
    for (std::size_t i = 0; i < N; ++i) out[i] = point(j[i]);
    return out;
}

TeacherEye eyeFrom(const nlohmann::json& j) {
    TeacherEye e;
    e.iris_centre = point(j.at("center"));
    e.iris_contour = points<4>(j.at("contour"));
    e.upper_lid = points<7>(j.at("eyelid_upper"));
    e.lower_lid = points<9>(j.at("eyelid_lower"));
    return e;
}

/// y of a polyline (sorted by x) at x, clamped to its ends.
float yAt(const std::vector<Point2>& line, float x) {
    if (x <= line.front().x) return line.front().y;
    for (std::size_t i = 1; i < line.size(); ++i) {
        if (x <= line[i].x) {
            const float t = (x - line[i - 1].x) / std::max(line[i].x - line[i - 1].x, 1e-6f);
            return line[i - 1].y + t * (line[i].y - line[i - 1].y);
        }
    }
    return line.back().y;
}
}  // namespace

float TeacherEye::irisRadius() const {
    float r = 0.f;
    for (const Point2& p : iris_contour) r += std::hypot(p.x - iris_centre.x, p.y - iris_centre.y) / 4.f;
    return r;
}

float TeacherEye::aperture() const {
    const Point2 o = lower_lid[0], in = lower_lid[8];
    const float width = std::hypot(in.x - o.x, in.y - o.y);
    if (!(width > 1e-3f)) return 0.f;
    const float ux = (in.x - o.x) / width, uy = (in.y - o.y) / width;
    // Along the axis (0..1) and across it (px, positive one side) for each lid.
    const auto profile = [&](auto first, auto last, bool withCorners) {
        std::vector<Point2> line;
        if (withCorners) line.push_back({0.f, 0.f});
        for (auto p = first; p != last; ++p) {
            const float dx = p->x - o.x, dy = p->y - o.y;
            line.push_back({(dx * ux + dy * uy) / width, -dx * uy + dy * ux});
        }
        if (withCorners) line.push_back({1.f, -(in.x - o.x) * uy + (in.y - o.y) * ux});
        std::sort(line.begin(), line.end(), [](const Point2& a, const Point2& b) { return a.x < b.x; });
        return line;
    };
    const auto upper = profile(upper_lid.begin(), upper_lid.end(), true);
    const auto lower = profile(lower_lid.begin(), lower_lid.end(), false);
    float gap = 0.f;
    for (const float s : {0.35f, 0.5f, 0.65f}) gap += std::fabs(yAt(lower, s) - yAt(upper, s)) / 3.f;
    return gap / width;
}

std::string teacherKey(const std::string& clip, int frame) { return clip + "#" + std::to_string(frame); }

std::map<std::string, TeacherRecord> readTeacher(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw Error("cannot read teacher labels '" + path + "'");
    std::map<std::string, TeacherRecord> records;
    std::string line;
    while (std::getline(in, line)) {
        if (line.empty()) continue;
        const auto j = nlohmann::json::parse(line);
        if (!j.value("found", false)) continue;
        TeacherRecord r;
        r.left = eyeFrom(j.at("left_iris"));
        r.right = eyeFrom(j.at("right_iris"));
        r.left.in_pts_eye = j.value("left_in_pts_eye", true);
        r.right.in_pts_eye = j.value("right_in_pts_eye", true);
        const std::string key = j.contains("image") ? j.at("image").get<std::string>()
                                                    : teacherKey(j.at("clip").get<std::string>(), j.at("frame").get<int>());
        records.emplace(key, r);
    }
    return records;
}

PatchLabels patchLabels(const TeacherEye& eye, const gaze::EyePatch& patch) {
    PatchLabels l;
    l.upper.push_back(gaze::toPatch(patch, eye.lower_lid[0]));
    for (const Point2& p : eye.upper_lid) l.upper.push_back(gaze::toPatch(patch, p));
    l.upper.push_back(gaze::toPatch(patch, eye.lower_lid[8]));
    for (const Point2& p : eye.lower_lid) l.lower.push_back(gaze::toPatch(patch, p));
    const auto byX = [](const Point2& a, const Point2& b) { return a.x < b.x; };
    std::sort(l.upper.begin(), l.upper.end(), byX);
    std::sort(l.lower.begin(), l.lower.end(), byX);
    l.iris_centre = gaze::toPatch(patch, eye.iris_centre);
    l.iris_radius = eye.irisRadius() / patch.image_px_per_patch_px;
    l.aperture = eye.aperture();
    return l;
}

int PatchLabels::pixelClass(float x, float y) const {
    if (x < upper.front().x || x > upper.back().x) return gaze::kSkin;
    const float top = yAt(upper, x), bottom = yAt(lower, x);
    if (!(y > std::min(top, bottom) && y < std::max(top, bottom))) return gaze::kSkin;
    return std::hypot(x - iris_centre.x, y - iris_centre.y) < iris_radius ? gaze::kIris : gaze::kSclera;
}

}  // namespace facetrack::tools
