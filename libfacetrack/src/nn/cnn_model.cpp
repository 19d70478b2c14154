#include "facetrack/cnn_model.hpp"

#include "core/binary_io.hpp"
#include "facetrack/version.hpp"
#include "model/internals.hpp"
#include "nn/cnn_model_data.hpp"

#include <algorithm>
#include <cmath>

namespace facetrack {

namespace nn {

namespace {
constexpr int kMaxStages = 8, kMaxRounds = 8;

void validateGeometry(const CnnModelData& m, const std::string& what) {
    if (m.geometry_net.empty()) {
        if (!m.geometry_reported.empty() || !m.geometry_neutral.empty() || !m.geometry_full.empty() || !m.lip_net.empty())
            throw Error(what + ": corrupt: geometry readings or a lip net without the geometry net");
        return;
    }
    if (!m.lip_net.empty() && (m.lip_patch_size < 16 || m.lip_patch_size > 256 || !(m.lip_patch_half > 0.f && m.lip_patch_half <= 4.f)))
        throw Error(what + ": corrupt: the lip net's patch");
    int inputs = kGeometryFeatures + (m.lip_net.empty() ? 0 : 2 * kLipPoints);
    for (const DenseLayer& l : m.geometry_net) {
        if (l.cols != inputs || l.rows < 1 || l.rows > 4096 || l.weight.size() != static_cast<std::size_t>(l.rows) * l.cols ||
            l.bias.size() != static_cast<std::size_t>(l.rows))
            throw Error(what + ": corrupt: a geometry net layer");
        for (const float v : l.weight) {
            if (!std::isfinite(v)) throw Error(what + ": corrupt: a geometry net weight");
        }
        for (const float v : l.bias) {
            if (!std::isfinite(v)) throw Error(what + ": corrupt: a geometry net weight");
        }
        inputs = l.rows;
    }
    const std::size_t n = m.expressions.size();
    if (static_cast<std::size_t>(inputs) != n || m.geometry_reported.size() != n || m.geometry_neutral.size() != n ||
        m.geometry_full.size() != n)
        throw Error(what + ": corrupt: the geometry net's outputs");
    for (std::size_t k = 0; k < n; ++k) {
        if (!(m.geometry_neutral[k] >= 0.f && m.geometry_neutral[k] < m.geometry_full[k] && m.geometry_full[k] <= 1.f))
            throw Error(what + ": corrupt: a geometry reading's neutral or full value");
    }
}

void validate(const CnnModelData& m, const std::string& what) {
    if (m.patch_size < 16 || m.patch_size > 256) throw Error(what + ": corrupt: patch size");
    if (m.stages.empty() || m.stages.size() > kMaxStages) throw Error(what + ": corrupt: stage count");
    if (!m.neutral.empty() && m.neutral.size() != m.expressions.size()) throw Error(what + ": corrupt: neutral weights");
    if (!m.reported.empty() && m.reported.size() != m.expressions.size()) throw Error(what + ": corrupt: reported expressions");
    for (const float w : m.neutral) {
        if (!(w >= 0.f && w < 1.f)) throw Error(what + ": corrupt: a neutral weight outside [0, 1)");
    }
    if (!m.full.empty() && m.full.size() != m.neutral.size()) throw Error(what + ": corrupt: full-expression readings");
    for (std::size_t k = 0; k < m.full.size(); ++k) {
        if (!(m.full[k] > m.neutral[k] && m.full[k] <= 1.f)) throw Error(what + ": corrupt: a full-expression reading outside (w0, 1]");
    }
    if (m.corrects_fit && !m.expressions_only) {
        throw Error(what + ": corrupt: correcting the fit's shapes is a mode of a stage that reads expressions");
    }
    for (const auto& s : m.stages) {
        if (s.rounds < 1 || s.rounds > kMaxRounds || s.onnx.empty()) throw Error(what + ": corrupt: a stage");
    }
    validateGeometry(m, what);
}
}  // namespace

std::vector<int> expressionIndices(const std::vector<std::string>& modelNames, const std::vector<std::string>& names) {
    std::vector<int> indices;
    for (const auto& name : names) {
        const auto it = std::find(modelNames.begin(), modelNames.end(), name);
        if (it == modelNames.end()) throw Error("CNN cascade: the face model has no expression '" + name + "'");
        indices.push_back(static_cast<int>(it - modelNames.begin()));
    }
    return indices;
}

void writeCnnModel(const std::string& path, const CnnModelData& m) {
    validate(m, "CNN cascade for '" + path + "'");
    core::BinaryWriter w;
    w.put<std::int32_t>(m.patch_size);
    w.put<std::uint32_t>(static_cast<std::uint32_t>(m.expressions.size()));
    for (const auto& name : m.expressions) w.putString(name);
    w.put<std::uint32_t>(static_cast<std::uint32_t>(m.stages.size()));
    for (const auto& s : m.stages) {
        w.put<std::int32_t>(s.rounds);
        w.putString(s.onnx);
    }
    w.putString(m.landmark_net);
    w.putString(m.provenance);
    w.put<std::uint8_t>(m.expressions_only ? 1 : 0);
    w.put<std::uint32_t>(static_cast<std::uint32_t>(m.neutral.size()));
    for (const float v : m.neutral) w.put<float>(v);
    w.put<std::uint32_t>(static_cast<std::uint32_t>(m.reported.size()));
    for (const bool v : m.reported) w.put<std::uint8_t>(v ? 1 : 0);
    w.put<std::uint8_t>(m.mirror_averaged ? 1 : 0);
    w.put<std::uint8_t>(m.corrects_fit ? 1 : 0);
    w.put<std::uint32_t>(static_cast<std::uint32_t>(m.full.size()));
    for (const float v : m.full) w.put<float>(v);
    w.put<std::uint32_t>(static_cast<std::uint32_t>(m.geometry_net.size()));
    for (const DenseLayer& l : m.geometry_net) {
        w.put<std::int32_t>(l.rows);
        w.put<std::int32_t>(l.cols);
        for (const float v : l.weight) w.put<float>(v);
        for (const float v : l.bias) w.put<float>(v);
    }
    if (!m.geometry_net.empty()) {
        for (std::size_t k = 0; k < m.expressions.size(); ++k) {
            w.put<std::uint8_t>(m.geometry_reported[k] ? 1 : 0);
            w.put<float>(m.geometry_neutral[k]);
            w.put<float>(m.geometry_full[k]);
        }
    }
    w.putString(m.lip_net);
    w.put<std::int32_t>(m.lip_patch_size);
    w.put<float>(m.lip_patch_half);
    core::writeModelFile(path, kCnnModelMagic, kCnnModelVersion, w.bytes());
}

CnnModelData readCnnModel(const std::string& path) {
    core::ModelFileReader file(path, kCnnModelMagic, 2, kCnnModelVersion, "CNN cascade");
    core::BinaryReader& r = file.reader();
    const std::uint32_t version = file.version();
    const std::string& what = file.what();
    CnnModelData m;
    m.patch_size = r.get<std::int32_t>();
    const auto names = r.get<std::uint32_t>();
    if (names > 1000) r.fail("expression count");
    for (std::uint32_t i = 0; i < names; ++i) m.expressions.push_back(r.getString());
    const auto stages = r.get<std::uint32_t>();
    if (stages > kMaxStages) r.fail("stage count");
    for (std::uint32_t i = 0; i < stages; ++i) {
        CnnStageData s;
        s.rounds = r.get<std::int32_t>();
        s.onnx = r.getString();
        m.stages.push_back(std::move(s));
    }
    m.landmark_net = r.getString();
    m.provenance = r.getString();
    if (version >= 3) {
        const auto mode = r.get<std::uint8_t>();
        if (mode > 1) r.fail("mode");
        m.expressions_only = mode == 1;
        const auto neutral = r.get<std::uint32_t>();
        if (neutral > names) r.fail("neutral weight count");
        for (std::uint32_t i = 0; i < neutral; ++i) m.neutral.push_back(r.get<float>());
        const auto reported = r.get<std::uint32_t>();
        if (reported > names) r.fail("reported expression count");
        for (std::uint32_t i = 0; i < reported; ++i) {
            const auto flag = r.get<std::uint8_t>();
            if (flag > 1) r.fail("a reported flag");
            m.reported.push_back(flag == 1);
        }
    }
    if (version >= 4 && version <= 9) {  // the landmark refiner, now a file of its own: skipped
        const bool refiner = !r.getString().empty();
        r.get<std::int32_t>();
        for (int i = 0; refiner && i < 136 + 68; ++i) r.get<float>();
        if (version >= 5) r.get<float>(), r.get<float>();
        if (version >= 6) {
            const bool sides = !r.getString().empty();
            r.get<std::int32_t>();
            for (int i = 0; sides && i < 22 + 11; ++i) r.get<float>();
        }
    }
    if (version >= 7) {
        const auto mirrored = r.get<std::uint8_t>();
        if (mirrored > 1) r.fail("the mirror-averaging flag");
        m.mirror_averaged = mirrored == 1;
        const auto corrects = r.get<std::uint8_t>();
        if (corrects > 1) r.fail("the fit-correcting flag");
        m.corrects_fit = corrects == 1;
    }
    if (version >= 8) {
        const auto full = r.get<std::uint32_t>();
        if (full > names) r.fail("full-expression reading count");
        for (std::uint32_t i = 0; i < full; ++i) m.full.push_back(r.get<float>());
    }
    if (version >= 9) {
        const auto layers = r.get<std::uint32_t>();
        if (layers > 8) r.fail("geometry net layer count");
        for (std::uint32_t i = 0; i < layers; ++i) {
            DenseLayer l;
            l.rows = r.get<std::int32_t>();
            l.cols = r.get<std::int32_t>();
            if (l.rows < 1 || l.rows > 4096 || l.cols < 1 || l.cols > 4096) r.fail("a geometry net layer's size");
            l.weight.resize(static_cast<std::size_t>(l.rows) * static_cast<std::size_t>(l.cols));
            for (float& v : l.weight) v = r.get<float>();
            l.bias.resize(static_cast<std::size_t>(l.rows));
            for (float& v : l.bias) v = r.get<float>();
            m.geometry_net.push_back(std::move(l));
        }
        if (layers > 0) {
            for (std::uint32_t i = 0; i < names; ++i) {
                const auto flag = r.get<std::uint8_t>();
                if (flag > 1) r.fail("a geometry reported flag");
                m.geometry_reported.push_back(flag == 1);
                m.geometry_neutral.push_back(r.get<float>());
                m.geometry_full.push_back(r.get<float>());
            }
        }
    }
    if (version >= 11) {
        m.lip_net = r.getString();
        m.lip_patch_size = r.get<std::int32_t>();
        m.lip_patch_half = r.get<float>();
    }
    r.expectEnd();
    validate(m, what);
    return m;
}

}  // namespace nn

CnnModel::CnnModel(std::shared_ptr<const nn::CnnModelData> data, std::string source) : data_(std::move(data)), source_(std::move(source)) {
    if (!data_) throw Error("CnnModel: null model data");
}

std::shared_ptr<const CnnModel> CnnModel::load(const std::string& path) { return model::Internals::make(nn::readCnnModel(path), path); }

std::string CnnModel::defaultPath() { return modelDirectory() + "/cnn_cascade.ftm"; }

std::uint32_t CnnModel::formatVersion() { return nn::kCnnModelVersion; }

const std::string& CnnModel::sourcePath() const { return source_; }

const std::string& CnnModel::provenance() const { return data_->provenance; }

std::vector<int> CnnModel::rounds() const {
    std::vector<int> r;
    for (const auto& s : data_->stages) r.push_back(s.rounds);
    return r;
}

bool CnnModel::hasLandmarkNet() const { return !data_->landmark_net.empty(); }

bool CnnModel::expressionsOnly() const { return data_->expressions_only; }

}  // namespace facetrack
