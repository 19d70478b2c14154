#include "data/profile/face_profiling.hpp"

#include "expression/landmark_net.hpp"
#include "facetrack/error.hpp"
#include "fit/fit_basis.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/photo.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

namespace facetrack::profile {

namespace {

constexpr double kDepthSlackCm = 0.3;  // a vertex this close behind the source's z-buffer counts as seen

/// Calls onPixel(x, y, w) for every integer pixel (x, y) inside the frame and
/// the triangle (a, b, c), w its barycentric weights.
template <class OnPixel>
void rasterize(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c, int width, int height, OnPixel&& onPixel) {
    const double area = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    if (std::abs(area) < 1e-12) return;
    const int x0 = std::max(0, static_cast<int>(std::ceil(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(width - 1, static_cast<int>(std::floor(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::ceil(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(height - 1, static_cast<int>(std::floor(std::max({a.y(), b.y(), c.y()}))));
    for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
            const Eigen::Vector2d p(x, y);
            const double wb = ((p - a).x() * (c - a).y() - (p - a).y() * (c - a).x()) / area;
            const double wc = ((b - a).x() * (p - a).y() - (b - a).y() * (p - a).x()) / area;
            const double wa = 1.0 - wb - wc;
            if (wa < -1e-9 || wb < -1e-9 || wc < -1e-9) continue;
            onPixel(x, y, Eigen::Vector3d(wa, wb, wc));
        }
    }
}

struct View {
    Eigen::Matrix3Xd points;     ///< camera frame, cm
    Eigen::Matrix2Xd projected;  ///< pixels
};

View viewOf(const std::vector<Vec3>& verticesMm, const core::Camera& camera, const fit::FaceParams& pose) {
    const Eigen::Matrix3d r = fit::rotationOf(pose.omega()) * fit::modelToFrontal();
    View v{Eigen::Matrix3Xd(3, static_cast<Eigen::Index>(verticesMm.size())),
           Eigen::Matrix2Xd(2, static_cast<Eigen::Index>(verticesMm.size()))};
    for (std::size_t i = 0; i < verticesMm.size(); ++i) {
        const auto k = static_cast<Eigen::Index>(i);
        v.points.col(k) = r * Eigen::Vector3d(verticesMm[i].x, verticesMm[i].y, verticesMm[i].z) / 10.0 + pose.translation();
        v.projected.col(k) = camera.project<double>(v.points.col(k));
    }
    return v;
}

/// +1 or -1: the sign of n . p (n the winding's normal) for triangles facing away
/// from the camera, found on the face region of the photographed view.
double awaySign(const View& v, const std::vector<std::array<int, 3>>& triangles, int faceVertices) {
    int towards = 0, away = 0;
    for (const auto& t : triangles) {
        if (t[0] >= faceVertices) continue;
        const Eigen::Vector3d n = (v.points.col(t[1]) - v.points.col(t[0])).cross(v.points.col(t[2]) - v.points.col(t[0]));
        (n.dot(v.points.col(t[0])) < 0 ? towards : away) += 1;
    }
    return towards >= away ? 1.0 : -1.0;  // most of the face region faces the camera
}

bool facesCamera(const View& v, const std::array<int, 3>& t, double away) {
    const Eigen::Vector3d n = (v.points.col(t[1]) - v.points.col(t[0])).cross(v.points.col(t[2]) - v.points.col(t[0]));
    return away * n.dot(v.points.col(t[0])) < 0 && v.points(2, t[0]) > 0 && v.points(2, t[1]) > 0 && v.points(2, t[2]) > 0;
}

/// The background's source position per output pixel: a piecewise affine map
/// fixed on the frame border and taking the photographed head's outline (the
/// convex hull of its projection) where the turned head puts those points.
void backgroundMap(const View& photographed, const View& turned, int width, int height, cv::Mat& mapX, cv::Mat& mapY) {
    std::vector<cv::Point2f> outline;
    std::vector<int> ids;
    for (Eigen::Index i = 0; i < photographed.projected.cols(); ++i) {
        if (turned.points(2, i) <= 0 || photographed.points(2, i) <= 0) continue;
        outline.emplace_back(static_cast<float>(photographed.projected(0, i)), static_cast<float>(photographed.projected(1, i)));
        ids.push_back(static_cast<int>(i));
    }
    std::vector<int> hull;
    if (outline.size() >= 3) cv::convexHull(outline, hull, false, false);
    std::vector<Eigen::Vector2d> to, from;
    for (int h : hull) {
        const auto i = static_cast<Eigen::Index>(ids[static_cast<std::size_t>(h)]);
        to.emplace_back(turned.projected.col(i));
        from.emplace_back(photographed.projected.col(i));
    }
    constexpr int kBorderSteps = 4;
    for (int k = 0; k < kBorderSteps; ++k) {
        const double f = static_cast<double>(k) / kBorderSteps;
        for (const Eigen::Vector2d& p : {Eigen::Vector2d(f * (width - 1), 0), Eigen::Vector2d(width - 1, f * (height - 1)),
                                         Eigen::Vector2d((1 - f) * (width - 1), height - 1), Eigen::Vector2d(0, (1 - f) * (height - 1))}) {
            to.push_back(p);
            from.push_back(p);
        }
    }
    double minX = 0, minY = 0, maxX = width, maxY = height;
    for (const auto& p : to)
        minX = std::min(minX, p.x()), minY = std::min(minY, p.y()), maxX = std::max(maxX, p.x()), maxY = std::max(maxY, p.y());
    cv::Subdiv2D subdiv(cv::Rect(static_cast<int>(std::floor(minX)) - 1, static_cast<int>(std::floor(minY)) - 1,
                                 static_cast<int>(std::ceil(maxX - minX)) + 3, static_cast<int>(std::ceil(maxY - minY)) + 3));
    std::map<std::pair<float, float>, std::size_t> index;
    for (std::size_t i = 0; i < to.size(); ++i) {
        const cv::Point2f p(static_cast<float>(to[i].x()), static_cast<float>(to[i].y()));
        if (index.emplace(std::make_pair(p.x, p.y), i).second) subdiv.insert(p);
    }
    std::vector<cv::Vec6f> triangles;
    subdiv.getTriangleList(triangles);
    mapX.create(height, width, CV_32F);
    mapY.create(height, width, CV_32F);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) mapX.at<float>(y, x) = static_cast<float>(x), mapY.at<float>(y, x) = static_cast<float>(y);
    for (const cv::Vec6f& t : triangles) {
        std::array<std::size_t, 3> corner{};
        bool known = true;
        for (int k = 0; k < 3; ++k) {
            const auto it = index.find({t[2 * k], t[2 * k + 1]});
            if (it == index.end()) known = false;  // one of Subdiv2D's outer helper vertices
            else corner[static_cast<std::size_t>(k)] = it->second;
        }
        if (!known) continue;
        rasterize(to[corner[0]], to[corner[1]], to[corner[2]], width, height, [&](int x, int y, const Eigen::Vector3d& w) {
            const Eigen::Vector2d s = w[0] * from[corner[0]] + w[1] * from[corner[1]] + w[2] * from[corner[2]];
            mapX.at<float>(y, x) = static_cast<float>(s.x());
            mapY.at<float>(y, x) = static_cast<float>(s.y());
        });
    }
}

}  // namespace

std::vector<ProfiledCopy> profiledCopies(const FaceModel& model, const cv::Mat& source, const core::Camera& camera,
                                         const std::vector<float>& identity, const std::vector<float>& expression,
                                         const fit::FaceParams& label, int tries, std::mt19937& rng) {
    constexpr double kMaxHidden = 0.15, kMaxYawDeg = 85.0;
    const double yaw = fit::eulerDegrees(label.omega()).y();
    const double lowest = std::max(std::abs(yaw) + 10.0, 25.0);
    std::vector<ProfiledCopy> copies;
    if (lowest >= kMaxYawDeg) return copies;
    std::uniform_real_distribution<double> target(lowest, kMaxYawDeg), coin(0.0, 1.0);
    for (int n = 0; n < tries; ++n) {
        const double side = std::abs(yaw) > 3.0 ? (yaw > 0 ? 1.0 : -1.0) : (coin(rng) < 0.5 ? -1.0 : 1.0);
        const fit::FaceParams turned = turnedBy(label, side * (target(rng) - std::abs(yaw)));
        ProfiledFace face = profileFace(model, source, camera, identity, expression, label, turned);
        if (face.hidden_share <= kMaxHidden) copies.push_back({std::move(face.image), turned});
    }
    return copies;
}

namespace {

/// Shapes expression warping never raises above the photograph's: they open the mouth or the
/// eyes, and the photograph has no texture of a mouth's inside or an eyeball's hidden part. The
/// eye's look shapes and the model's extras (no ARKit shape) stay as photographed too.
bool keptAsPhotographed(const std::string& name) {
    for (const char* prefix :
         {"jawOpen", "mouthLowerDown", "mouthUpperUp", "eyeWide", "eyeLook", "PupilDilate", "cheekRaiser", "mouthClose"})
        if (name.rfind(prefix, 0) == 0) return true;
    return false;
}

/// The named groups of shapes a copy moves together: the earlier four, then every shape the
/// face model has that warping may raise, alone, and for a left/right pair both sides at once.
std::map<std::string, std::vector<std::string>> copyGroups(const std::vector<std::string>& names) {
    std::map<std::string, std::vector<std::string>> groups = {
        {"brows_down", {"browDown_L", "browDown_R"}},
        {"inner_brows_up", {"browInnerUp_L", "browInnerUp_R"}},
        {"brows_up", {"browInnerUp_L", "browInnerUp_R", "browOuterUp_L", "browOuterUp_R"}},
        {"pucker", {"mouthPucker"}}};
    for (const std::string& name : names) {
        if (keptAsPhotographed(name) || name.rfind("eyeBlink", 0) == 0) continue;  // a blink is the gaze stage's, from real eyes
        groups[name] = {name};
        if (name.size() > 2 && name.compare(name.size() - 2, 2, "_L") == 0)
            groups[name.substr(0, name.size() - 2)] = {name, name.substr(0, name.size() - 2) + "_R"};
    }
    return groups;
}

}  // namespace

std::vector<std::string> expressionCopyGroups(const FaceModel& model) {
    std::vector<std::string> out;
    for (const auto& [name, shapes] : copyGroups(model.expressionNames())) out.push_back(name);
    return out;
}

std::vector<ProfiledCopy> expressionCopies(const FaceModel& model, const cv::Mat& source, const core::Camera& camera,
                                           const std::vector<float>& identity, const std::vector<int>& expressions,
                                           const fit::FaceParams& label, int count, std::mt19937& rng,
                                           const std::vector<std::string>& groups, const std::vector<std::vector<float>>& captures) {
    constexpr double kMaxHidden = 0.15, kMaxWeight = 0.9;
    const auto kGroups = copyGroups(model.expressionNames());
    std::vector<const std::vector<std::string>*> drawn;
    for (const auto& [name, shapes] : kGroups) {
        if (groups.empty() || std::find(groups.begin(), groups.end(), name) != groups.end()) drawn.push_back(&shapes);
    }
    const bool captured = !captures.empty() && (groups.empty() || std::find(groups.begin(), groups.end(), "captured") != groups.end());
    for (const auto& name : groups) {
        if (!kGroups.count(name) && name != "captured") throw Error("expressionCopies: no group of shapes is called '" + name + "'");
        if (name == "captured" && captures.empty()) throw Error("expressionCopies: the group 'captured' needs captured faces");
    }
    const auto& names = model.expressionNames();
    auto positionOf = [&](const std::string& name) {  // in the label's expressions, or -1
        for (std::size_t k = 0; k < expressions.size(); ++k) {
            if (names[static_cast<std::size_t>(expressions[k])] == name) return static_cast<Eigen::Index>(k);
        }
        return Eigen::Index{-1};
    };
    // A draw is a captured face with probability (groups' share): one more "group" among the named.
    const std::size_t choices = drawn.size() + (captured ? 1 : 0);
    std::uniform_int_distribution<std::size_t> group(0, choices - 1);
    std::uniform_int_distribution<std::size_t> capture(0, captures.empty() ? 0 : captures.size() - 1);
    std::uniform_real_distribution<double> weight(0.0, kMaxWeight);
    const std::vector<float> photographed = nativeWeights(model, expressions, label.expression);
    std::vector<ProfiledCopy> copies;
    for (int n = 0; n < count; ++n) {
        fit::FaceParams moved = label;
        const std::size_t g = group(rng);
        if (g < drawn.size()) {
            const double w = weight(rng);
            for (const auto& name : *drawn[g]) {
                if (const Eigen::Index k = positionOf(name); k >= 0) moved.expression[k] = w;
            }
        } else {  // a real face's expression in place of the photograph's
            const std::vector<float>& face = captures[capture(rng)];
            for (std::size_t k = 0; k < expressions.size(); ++k) {
                const auto e = static_cast<std::size_t>(expressions[k]);
                const auto i = static_cast<Eigen::Index>(k);
                moved.expression[i] = keptAsPhotographed(names[e]) ? std::min(label.expression[i], static_cast<double>(face[e]))
                                                                   : static_cast<double>(face[e]);
            }
        }
        ProfiledFace face = profileFace(model, source, camera, identity, photographed, label, label,
                                        nativeWeights(model, expressions, moved.expression));
        if (face.hidden_share <= kMaxHidden) copies.push_back({std::move(face.image), moved});
    }
    return copies;
}

std::vector<std::vector<float>> readArkitCaptures(const FaceModel& model, const std::string& directory, int every) {
    if (every < 1) throw Error("readArkitCaptures: every must be at least 1");
    std::vector<std::string> files;
    for (const auto& entry : std::filesystem::directory_iterator(directory))
        if (entry.path().extension() == ".csv") files.push_back(entry.path().string());
    std::sort(files.begin(), files.end());
    if (files.empty()) throw Error("no ARKit captures (*.csv) in '" + directory + "'");
    const auto& names = model.expressionNames();
    std::vector<std::vector<float>> faces;
    for (const std::string& path : files) {
        std::ifstream in(path);
        std::string line;
        if (!std::getline(in, line)) throw Error("'" + path + "' is empty");
        std::vector<std::string> header;
        std::stringstream h(line);
        for (std::string f; std::getline(h, f, ',');) header.push_back(f);
        // Live Link Face names a shape "MouthSmileLeft"; the face model "mouthSmile_L".
        std::vector<int> column(names.size(), -1);
        for (std::size_t e = 0; e < names.size(); ++e) {
            std::string arkit = names[e];
            if (arkit.size() > 2 && arkit.compare(arkit.size() - 2, 2, "_L") == 0) arkit = arkit.substr(0, arkit.size() - 2) + "Left";
            if (arkit.size() > 2 && arkit.compare(arkit.size() - 2, 2, "_R") == 0) arkit = arkit.substr(0, arkit.size() - 2) + "Right";
            arkit[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(arkit[0])));
            const auto it = std::find(header.begin(), header.end(), arkit);
            if (it != header.end()) column[e] = static_cast<int>(it - header.begin());
        }
        for (int row = 0; std::getline(in, line); ++row) {
            if (row % every != 0) continue;
            std::vector<std::string> f;
            std::stringstream s(line);
            for (std::string v; std::getline(s, v, ',');) f.push_back(v);
            if (f.size() != header.size()) continue;  // a cut last line
            std::vector<float> w(names.size(), 0.f);
            for (std::size_t e = 0; e < names.size(); ++e)
                if (column[e] >= 0) w[e] = std::clamp(std::stof(f[static_cast<std::size_t>(column[e])]), 0.f, 1.f);
            faces.push_back(std::move(w));
        }
    }
    return faces;
}

std::vector<ProfiledCopy> turnSequence(const FaceModel& model, const cv::Mat& source, const core::Camera& camera,
                                       const std::vector<float>& identity, const std::vector<float>& expression,
                                       const fit::FaceParams& label, double stepDeg) {
    constexpr double kMaxHidden = 0.15, kMaxYawDeg = 80.0;
    if (!(stepDeg >= 0.5 && stepDeg <= 20.0)) throw Error("turnSequence: the step must be in [0.5, 20] degrees");
    const double yaw = fit::eulerDegrees(label.omega()).y();
    std::vector<ProfiledCopy> frames;
    frames.push_back({profileFace(model, source, camera, identity, expression, label, label).image, label});
    for (const double side : {1.0, -1.0}) {
        std::vector<ProfiledCopy> out;  // the leg away from y0; it comes back the same way
        for (double turn = stepDeg; side * yaw + turn <= kMaxYawDeg; turn += stepDeg) {
            const fit::FaceParams turned = turnedBy(label, side * turn);
            ProfiledFace face = profileFace(model, source, camera, identity, expression, label, turned);
            if (face.hidden_share > kMaxHidden) break;
            out.push_back({std::move(face.image), turned});
        }
        if (out.empty()) continue;
        frames.insert(frames.end(), out.begin(), out.end());
        for (auto back = out.rbegin() + 1; back != out.rend(); ++back) frames.push_back(*back);
        frames.push_back(frames.front());
    }
    return frames;
}

std::vector<float> nativeWeights(const FaceModel& model, const std::vector<int>& ids, const Eigen::VectorXd& weights) {
    std::vector<float> native(model.expressionNames().size(), 0.f);
    for (std::size_t k = 0; k < ids.size() && k < static_cast<std::size_t>(weights.size()); ++k)
        native[static_cast<std::size_t>(ids[k])] = static_cast<float>(weights[static_cast<Eigen::Index>(k)]);
    return native;
}

fit::FaceParams turnedBy(const fit::FaceParams& params, double yawDeg) {
    fit::FaceParams out = params;
    const Eigen::AngleAxisd r(fit::rotationOf(fit::omegaFromEuler(Eigen::Vector3d(0, yawDeg, 0))) * fit::rotationOf(params.omega()));
    out.pose.head<3>() = r.angle() * r.axis();
    return out;
}

ProfiledFace profileFace(const FaceModel& model, const cv::Mat& source, const core::Camera& camera, const std::vector<float>& identity,
                         const std::vector<float>& expression, const fit::FaceParams& photographed, const fit::FaceParams& turned,
                         const std::vector<float>& turnedExpression) {
    if (source.empty() || source.depth() != CV_8U || (source.channels() != 1 && source.channels() != 3)) {
        throw Error("profileFace: expected an 8-bit grey or colour image");
    }
    const int width = source.cols, height = source.rows;
    const std::vector<Vec3> vertices = model.vertices(identity, expression);
    const auto triangles = model.triangles();
    const View from = viewOf(vertices, camera, photographed);
    const View to = viewOf(turnedExpression.empty() ? vertices : model.vertices(identity, turnedExpression), camera, turned);
    const double away = awaySign(from, triangles, model.faceVertexCount());

    // Which vertices the photograph shows: not behind its z-buffer.
    cv::Mat sourceDepth(height, width, CV_64F, cv::Scalar(std::numeric_limits<double>::infinity()));
    for (const auto& t : triangles) {
        if (!facesCamera(from, t, away)) continue;
        rasterize(from.projected.col(t[0]), from.projected.col(t[1]), from.projected.col(t[2]), width, height,
                  [&](int x, int y, const Eigen::Vector3d& w) {
                      const double z = w[0] * from.points(2, t[0]) + w[1] * from.points(2, t[1]) + w[2] * from.points(2, t[2]);
                      double& d = sourceDepth.at<double>(y, x);
                      d = std::min(d, z);
                  });
    }
    std::vector<bool> seen(vertices.size(), false);
    for (Eigen::Index i = 0; i < from.projected.cols(); ++i) {
        const int x = static_cast<int>(std::lround(from.projected(0, i))), y = static_cast<int>(std::lround(from.projected(1, i)));
        if (x < 0 || y < 0 || x >= width || y >= height) continue;
        seen[static_cast<std::size_t>(i)] = from.points(2, i) <= sourceDepth.at<double>(y, x) + kDepthSlackCm;
    }

    cv::Mat mapX, mapY;
    backgroundMap(from, to, width, height, mapX, mapY);
    cv::Mat depth(height, width, CV_64F, cv::Scalar(std::numeric_limits<double>::infinity()));
    cv::Mat hidden(height, width, CV_8U, cv::Scalar(2));  // 2: background, 1: hidden in the source, 0: seen
    for (const auto& t : triangles) {
        if (!facesCamera(to, t, away)) continue;
        const bool wasSeen = facesCamera(from, t, away) && seen[static_cast<std::size_t>(t[0])] && seen[static_cast<std::size_t>(t[1])] &&
                             seen[static_cast<std::size_t>(t[2])];
        rasterize(to.projected.col(t[0]), to.projected.col(t[1]), to.projected.col(t[2]), width, height,
                  [&](int x, int y, const Eigen::Vector3d& w) {
                      const double z = w[0] * to.points(2, t[0]) + w[1] * to.points(2, t[1]) + w[2] * to.points(2, t[2]);
                      double& d = depth.at<double>(y, x);
                      if (z >= d) return;
                      d = z;
                      hidden.at<std::uint8_t>(y, x) = wasSeen ? 0 : 1;
                      if (!wasSeen) return;  // the background shows: the photograph has no texture for it
                      const Eigen::Vector2d s = w[0] * from.projected.col(t[0]) + w[1] * from.projected.col(t[1]) +
                                                w[2] * from.projected.col(t[2]);
                      mapX.at<float>(y, x) = static_cast<float>(s.x());
                      mapY.at<float>(y, x) = static_cast<float>(s.y());
                  });
    }
    ProfiledFace out;
    cv::remap(source, out.image, mapX, mapY, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    const cv::Mat holes = hidden == 1;
    if (cv::countNonZero(holes) > 0) cv::inpaint(out.image, holes, out.image, 3.0, cv::INPAINT_TELEA);
    const double head = static_cast<double>(cv::countNonZero(hidden < 2));
    out.hidden_share = head > 0 ? cv::countNonZero(holes) / head : 0.0;
    return out;
}

fit::Landmarks2d carriedLandmarks(const expression::WarpLayout& layout, const fit::FitBasis& basis, const Eigen::VectorXd& identity,
                                  const core::Camera& camera, const fit::FaceParams& label, const fit::Landmarks2d& landmarks,
                                  const fit::FaceParams& turned) {
    const Eigen::Matrix3Xd shape = fit::shapeWithIdentity(basis, identity);
    Eigen::Matrix3Xd slots;
    const Eigen::Matrix2d from = expression::patchToFrame(layout, expression::projectAnchors(layout, identity, camera, label));
    const Eigen::VectorXd d = expression::displacementsOf(from, expression::projectedLandmarks(basis, shape, camera, label, slots),
                                                          landmarks);
    return expression::displaced(expression::patchToFrame(layout, expression::projectAnchors(layout, identity, camera, turned)),
                                 expression::projectedLandmarks(basis, shape, camera, turned, slots), d);
}

}  // namespace facetrack::profile
