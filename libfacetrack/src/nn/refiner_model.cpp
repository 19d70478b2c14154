#include "facetrack/refiner_model.hpp"

#include "core/binary_io.hpp"
#include "facetrack/version.hpp"
#include "model/internals.hpp"
#include "nn/refiner_model_data.hpp"

namespace facetrack {

namespace nn {

namespace {

/// One net's layout: a patch size, `points` mean-shape points inside the patch, a share in [0, 1] each.
void validateLayout(int size, const std::vector<float>& mean, const std::vector<float>& share, std::size_t points, const std::string& what,
                    const std::string& net) {
    if (size < 16 || size > 256) throw Error(what + ": corrupt: the " + net + "'s patch size");
    if (mean.size() != 2 * points || share.size() != points) throw Error(what + ": corrupt: the " + net + "'s shape");
    for (const float v : mean) {
        if (!(v >= 0.f && v <= size)) throw Error(what + ": corrupt: the " + net + "'s mean shape outside its patch");
    }
    for (const float v : share) {
        if (!(v >= 0.f && v <= 1.f)) throw Error(what + ": corrupt: a " + net + " share outside [0, 1]");
    }
}

void validate(const RefinerModelData& m, const std::string& what) {
    if (m.net.empty()) throw Error(what + ": corrupt: no landmark refiner net");
    validateLayout(m.patch_size, m.mean, m.share, 68, what, "landmark refiner");
    if (!(m.trust_from >= 0.f && m.trust_to >= 0.f && m.trust_to <= 1.f)) throw Error(what + ": corrupt: the refiner's trust ramp");
    if (m.side_net.empty()) {
        if (!m.side_mean.empty() || !m.side_share.empty()) throw Error(what + ": corrupt: a brow and eye shape without its net");
        return;
    }
    validateLayout(m.side_patch_size, m.side_mean, m.side_share, 11, what, "brow and eye refiner");
}

}  // namespace

void writeRefinerModel(const std::string& path, const RefinerModelData& m) {
    validate(m, "landmark refiner for '" + path + "'");
    core::BinaryWriter w;
    w.putString(m.net);
    w.put<std::int32_t>(m.patch_size);
    for (const float v : m.mean) w.put<float>(v);
    for (const float v : m.share) w.put<float>(v);
    w.put<float>(m.trust_from);
    w.put<float>(m.trust_to);
    w.putString(m.side_net);
    w.put<std::int32_t>(m.side_patch_size);
    for (const float v : m.side_mean) w.put<float>(v);
    for (const float v : m.side_share) w.put<float>(v);
    w.putString(m.provenance);
    core::writeModelFile(path, kRefinerModelMagic, kRefinerModelVersion, w.bytes());
}

RefinerModelData readRefinerModel(const std::string& path) {
    core::ModelFileReader file(path, kRefinerModelMagic, kRefinerModelVersion, kRefinerModelVersion, "landmark refiner");
    core::BinaryReader& r = file.reader();
    RefinerModelData m;
    m.net = r.getString();
    m.patch_size = r.get<std::int32_t>();
    for (int i = 0; i < 136; ++i) m.mean.push_back(r.get<float>());
    for (int i = 0; i < 68; ++i) m.share.push_back(r.get<float>());
    m.trust_from = r.get<float>();
    m.trust_to = r.get<float>();
    m.side_net = r.getString();
    m.side_patch_size = r.get<std::int32_t>();
    if (!m.side_net.empty()) {
        for (int i = 0; i < 22; ++i) m.side_mean.push_back(r.get<float>());
        for (int i = 0; i < 11; ++i) m.side_share.push_back(r.get<float>());
    }
    m.provenance = r.getString();
    r.expectEnd();
    validate(m, file.what());
    return m;
}

}  // namespace nn

RefinerModel::RefinerModel(std::shared_ptr<const nn::RefinerModelData> data, std::string source)
    : data_(std::move(data)), source_(std::move(source)) {
    if (!data_) throw Error("RefinerModel: null model data");
}

std::shared_ptr<const RefinerModel> RefinerModel::load(const std::string& path) {
    return model::Internals::make(nn::readRefinerModel(path), path);
}

std::string RefinerModel::defaultPath() { return modelDirectory() + "/landmark_refiner.ftm"; }

std::uint32_t RefinerModel::formatVersion() { return nn::kRefinerModelVersion; }

const std::string& RefinerModel::sourcePath() const { return source_; }

const std::string& RefinerModel::provenance() const { return data_->provenance; }

bool RefinerModel::hasSideNet() const { return !data_->side_net.empty(); }

}  // namespace facetrack
