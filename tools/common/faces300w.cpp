#include "faces300w.hpp"

#include "core/binary_io.hpp"
#include "core/environment.hpp"
#include "facetrack/error.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <regex>

namespace fs = std::filesystem;

namespace facetrack::tools {

bool boxMatchesFace(const Box& box, const core::Shape2& points) {
    const Eigen::Vector2f size = points.rowwise().maxCoeff() - points.rowwise().minCoeff();
    const Eigen::Vector2f c = points.rowwise().mean();
    const bool contains = c.x() >= box.x0 && c.x() <= box.x1 && c.y() >= box.y0 && c.y() <= box.y1;
    const float ratio = std::sqrt(box.width() * box.height()) / std::sqrt(size.x() * size.y());
    return contains && ratio >= 0.5f && ratio <= 2.f;
}

std::optional<Box> matchingBox(const std::vector<Detection>& detections, const core::Shape2& points) {
    const Eigen::Vector2f lo = points.rowwise().minCoeff(), hi = points.rowwise().maxCoeff();
    std::optional<Box> best;
    float bestOverlap = -1.f;
    for (const auto& d : detections) {
        if (!boxMatchesFace(d.box, points)) continue;
        const float w = std::min(d.box.x1, hi.x()) - std::max(d.box.x0, lo.x());
        const float h = std::min(d.box.y1, hi.y()) - std::max(d.box.y0, lo.y());
        const float overlap = std::max(0.f, w) * std::max(0.f, h);
        if (overlap > bestOverlap) {
            best = d.box;
            bestOverlap = overlap;
        }
    }
    return best;
}

std::string faces300wRoot(const std::string& given) {
    if (!given.empty()) return given;
    const std::string shared = core::sharedDirectory();
    if (shared.empty()) throw Error("no --data given and ../shared not found");
    return shared + "/data/faces300w";
}

Split parseSplit(const std::string& name) {
    if (name == "train") return Split::Train;
    if (name == "validation") return Split::Validation;
    if (name == "test") return Split::Test;
    throw Error("unknown split '" + name + "' (train, validation or test)");
}

std::vector<AnnotatedImage> listAnnotated(const std::string& dir) {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) throw Error("not a folder: '" + dir + "'");
    std::vector<AnnotatedImage> out;
    for (const auto& entry : fs::recursive_directory_iterator(dir)) {
        const auto ext = entry.path().extension();
        if (ext != ".jpg" && ext != ".png" && ext != ".jpeg" && ext != ".pgm") continue;
        const fs::path pts = fs::path(entry.path()).replace_extension(".pts");
        if (!fs::exists(pts)) continue;
        out.push_back({entry.path().string(), pts.string(), fs::relative(entry.path().parent_path(), dir).string()});
    }
    std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.image < b.image; });
    return out;
}

namespace {
/// Validation membership, by source photo: "helen/trainset/100040721_2" -> "100040721".
bool isValidation(const AnnotatedImage& a) {
    if (a.subset != "helen/trainset" && a.subset != "lfpw/trainset") return false;
    std::string photo = fs::path(a.image).stem().string();
    if (a.subset == "helen/trainset") photo = std::regex_replace(photo, std::regex("_[0-9]+$"), "");
    const std::string key = a.subset + "/" + photo;
    return core::fnv1a64(key.data(), key.size()) % 10 == 0;
}
}  // namespace

std::vector<AnnotatedImage> list300W(const std::string& root, Split split) {
    std::vector<AnnotatedImage> out;
    const std::vector<std::string> subsets = split == Split::Test ? std::vector<std::string>{"helen/testset", "lfpw/testset"}
                                                                  : std::vector<std::string>{"helen/trainset", "lfpw/trainset", "afw"};
    for (const auto& subset : subsets) {
        for (auto& a : listAnnotated(root + "/" + subset)) {
            a.subset = subset;
            if (split == Split::Test || isValidation(a) == (split == Split::Validation)) out.push_back(std::move(a));
        }
    }
    if (out.empty()) throw Error("no annotated images for this split below '" + root + "'");
    return out;
}

}  // namespace facetrack::tools
