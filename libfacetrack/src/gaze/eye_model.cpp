#include "facetrack/eye_model.hpp"

#include "core/binary_io.hpp"
#include "facetrack/version.hpp"
#include "gaze/eye_model_data.hpp"
#include "gaze/iris_net.hpp"
#include "model/internals.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>

namespace facetrack {

namespace gaze {

namespace {
void putForest(core::BinaryWriter& w, const PatchForest& f) {
    w.put<std::int32_t>(f.depth);
    w.put<std::int32_t>(f.outputs);
    w.putVector(f.splits);
    w.putVector(f.leaves);
}

PatchForest getForest(core::BinaryReader& r) {
    PatchForest f;
    f.depth = r.get<std::int32_t>();
    f.outputs = r.get<std::int32_t>();
    if (f.depth < 1 || f.depth > 16 || f.outputs < 1 || f.outputs > 16) r.fail("forest sizes");
    f.splits = r.getVector<PatchFeature>();
    f.leaves = r.getVector<float>();
    return f;
}

void validate(const EyeModelData& m, const std::string& what) {
    m.pixels.validate(what.c_str());
    m.aperture.validate(what.c_str());
    if (m.pixels.outputs != kPixelClasses || m.aperture.outputs != 1) throw Error(what + ": corrupt: forest outputs");
    if (m.pixels.reach() > kPixelTestReach)
        throw Error(what + ": corrupt: pixel tests reach beyond " + std::to_string(kPixelTestReach) + " px");
    if (!(m.open_aperture > 0.f && m.open_aperture < 2.f && m.closed_aperture >= 0.f && m.closed_aperture < m.open_aperture))
        throw Error(what + ": corrupt: open or closed aperture");
    if (m.corner_stages.size() > kMaxCornerStages) throw Error(what + ": corrupt: corner stages");
    for (const PatchForest& f : m.corner_stages) {
        f.validate(what.c_str());
        if (f.outputs != 4) throw Error(what + ": corrupt: corner forest outputs");
    }
    if (!(m.open_map_scale > 0.1f && m.open_map_scale < 10.f && std::abs(m.open_map_offset) < 1.f))
        throw Error(what + ": corrupt: open-map scale or offset");
    if (m.net_map_radius < 0 || m.net_map_radius > kMaxNetMapRadius) throw Error(what + ": corrupt: the net maps' box radius");
    if (!m.iris_net.empty()) IrisNet(m.iris_net, what + ": its iris net");  // loads and runs once, or throws
}
}  // namespace

void writeEyeModel(const std::string& path, const EyeModelData& m) {
    validate(m, "eye model for '" + path + "'");
    core::BinaryWriter w;
    putForest(w, m.pixels);
    putForest(w, m.aperture);
    w.put(m.open_aperture);
    w.put(m.closed_aperture);
    w.putString(m.provenance);
    w.putString(m.iris_net);
    w.put<std::uint8_t>(static_cast<std::uint8_t>(m.corner_stages.size()));
    for (const PatchForest& f : m.corner_stages) putForest(w, f);
    w.put(m.open_map_scale);
    w.put(m.open_map_offset);
    w.put<std::int32_t>(m.net_map_radius);
    core::writeModelFile(path, kEyeModelMagic, kEyeModelVersion, w.bytes());
}

EyeModelData readEyeModel(const std::string& path) {
    core::ModelFileReader file(path, kEyeModelMagic, 1, kEyeModelVersion, "eye model");
    core::BinaryReader& r = file.reader();
    const std::uint32_t version = file.version();
    const std::string& what = file.what();
    EyeModelData m;
    m.pixels = getForest(r);
    m.aperture = getForest(r);
    m.open_aperture = r.get<float>();
    m.closed_aperture = r.get<float>();
    m.provenance = r.getString();
    if (version >= 2) m.iris_net = r.getString();
    if (version >= 3) {
        const std::size_t stages = r.get<std::uint8_t>();
        if (stages > kMaxCornerStages) r.fail("the number of corner stages");
        for (std::size_t k = 0; k < stages; ++k) m.corner_stages.push_back(getForest(r));
    }
    if (version >= 4) {
        m.open_map_scale = r.get<float>();
        m.open_map_offset = r.get<float>();
        m.net_map_radius = r.get<std::int32_t>();
    }
    r.expectEnd();
    validate(m, what);
    return m;
}

std::array<Point2, 2> refineCorners(const PatchForest& forest, const EyePatch& patch) {
    float d[4];
    forest.evaluate(patch.pixels, 0, 0, d);
    return {toImage(patch, {kOuterX + d[0], kCornerY + d[1]}), toImage(patch, {kInnerX + d[2], kCornerY + d[3]})};
}

std::array<Point2, 2> eyeCorners(const EyeModelData& model, const cv::Mat& gray, const EyePatch& patch, EyePatch& scratch) {
    std::array<Point2, 2> corners = {toImage(patch, {kOuterX, kCornerY}), toImage(patch, {kInnerX, kCornerY})};
    for (std::size_t k = 0; k < model.corner_stages.size(); ++k) {
        const EyePatch* at = &patch;
        if (k > 0) {
            if (!cutEyePatch(gray, corners[0], corners[1], patch.mirrored, scratch)) break;
            at = &scratch;
        }
        corners = refineCorners(model.corner_stages[k], *at);
    }
    return corners;
}

float openMapGap(const cv::Mat& open) {
    float gap = 0.f;
    for (const float share : {0.35f, 0.5f, 0.65f}) {
        const float x = (kOuterX + share * kEyeWidth - static_cast<float>(kClassifiedRegion.x0)) /
                        static_cast<float>(kClassifiedRegion.step);
        const int column = std::clamp(static_cast<int>(std::lround(x)), 0, kClassifiedRegion.columns() - 1);
        for (int row = 0; row < kClassifiedRegion.rows(); ++row) gap += open.at<float>(row, column);
    }
    return gap * static_cast<float>(kClassifiedRegion.step) / (3.f * kEyeWidth);
}

void boxSmooth(cv::Mat& map, int radius) {
    constexpr int kRows = kClassifiedRegion.rows(), kColumns = kClassifiedRegion.columns();
    if (map.rows != kRows || map.cols != kColumns || map.type() != CV_32F) throw Error("boxSmooth: not a classified-region map");
    if (radius <= 0) return;
    std::array<float, kRows * kColumns> across;  // the rows' sums along x, then the columns' along y
    const float norm = 1.f / static_cast<float>((2 * radius + 1) * (2 * radius + 1));
    for (int y = 0; y < kRows; ++y) {
        const float* row = map.ptr<float>(y);
        for (int x = 0; x < kColumns; ++x) {
            float sum = 0.f;
            for (int d = -radius; d <= radius; ++d) sum += row[std::clamp(x + d, 0, kColumns - 1)];
            across[static_cast<std::size_t>(y * kColumns + x)] = sum;
        }
    }
    for (int y = 0; y < kRows; ++y) {
        float* row = map.ptr<float>(y);
        for (int x = 0; x < kColumns; ++x) {
            float sum = 0.f;
            for (int d = -radius; d <= radius; ++d) sum += across[static_cast<std::size_t>(std::clamp(y + d, 0, kRows - 1) * kColumns + x)];
            row[x] = sum * norm;
        }
    }
}

void classifyByNet(const EyeModelData& model, IrisNet& net, const std::array<const cv::Mat*, 2>& patches,
                   const std::array<cv::Mat*, 2>& iris, const std::array<cv::Mat*, 2>& open) {
    net.classify(patches, iris, open);
    for (std::size_t e = 0; e < 2; ++e) {
        if (!patches[e]) continue;
        boxSmooth(*iris[e], model.net_map_radius);
        boxSmooth(*open[e], model.net_map_radius);
    }
}

void classifyByForest(const EyeModelData& model, const cv::Mat& patch, cv::Mat& padded, cv::Mat& iris, cv::Mat& open) {
    padPatch(patch, kPixelTestReach, padded);
    float p[kPixelClasses];
    for (int y = 0; y < kClassifiedRegion.rows(); ++y) {
        float* irisRow = iris.ptr<float>(y);
        float* openRow = open.ptr<float>(y);
        for (int x = 0; x < kClassifiedRegion.columns(); ++x) {
            model.pixels.evaluatePadded(padded, kPixelTestReach, kClassifiedRegion.x(x), kClassifiedRegion.y(y), p);
            irisRow[x] = p[kIris];
            openRow[x] = p[kIris] + p[kSclera];
        }
    }
}

}  // namespace gaze

EyeModel::EyeModel(std::shared_ptr<const gaze::EyeModelData> data, std::string source)
    : data_(std::move(data)), source_(std::move(source)) {
    if (!data_) throw Error("EyeModel: null model data");
}

std::shared_ptr<const EyeModel> EyeModel::load(const std::string& path) { return model::Internals::make(gaze::readEyeModel(path), path); }

std::shared_ptr<const EyeModel> EyeModel::loadDefault() { return load(defaultPath()); }

std::string EyeModel::defaultPath() { return modelDirectory() + "/eye_model.ftm"; }

std::uint32_t EyeModel::formatVersion() { return gaze::kEyeModelVersion; }

const std::string& EyeModel::sourcePath() const { return source_; }

const std::string& EyeModel::provenance() const { return data_->provenance; }

}  // namespace facetrack
