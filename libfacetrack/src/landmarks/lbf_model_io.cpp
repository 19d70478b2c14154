#include "core/binary_io.hpp"
#include "landmarks/lbf_model.hpp"

#include <cmath>

namespace facetrack::landmarks {

namespace {
[[noreturn]] void invalid(const std::string& what, const std::string& why) { throw Error(what + ": corrupt: " + why); }

void putShape(core::BinaryWriter& w, const Shape68& s) {
    w.put<std::uint32_t>(kLandmarks);
    w.putArray(s.data(), static_cast<std::size_t>(s.size()));
}

Shape68 getShape(core::BinaryReader& r) {
    const auto n = r.get<std::uint32_t>();
    if (n != kLandmarks) r.fail("a 68-point shape");
    Shape68 s;
    r.getArray(s.data(), static_cast<std::size_t>(s.size()));
    return s;
}
}  // namespace

void LbfStage::setRegression(const RegressionRows& rows) {
    regression.resize(rows.rows(), 2 * kLandmarks);
    row_scale.resize(static_cast<std::size_t>(rows.rows()));
    for (Eigen::Index r = 0; r < rows.rows(); ++r) {
        const float scale = rows.row(r).cwiseAbs().maxCoeff() / 127.f;
        row_scale[static_cast<std::size_t>(r)] = scale;
        for (int c = 0; c < 2 * kLandmarks; ++c) {
            regression(r, c) = static_cast<std::int8_t>(scale > 0.f ? std::lround(rows(r, c) / scale) : 0);
        }
    }
}

RegressionRows LbfStage::regressionRows() const {
    RegressionRows rows(regression.rows(), 2 * kLandmarks);
    for (Eigen::Index r = 0; r < rows.rows(); ++r) {
        rows.row(r) = row_scale[static_cast<std::size_t>(r)] * regression.row(r).cast<float>();
    }
    return rows;
}

void validate(const LbfModel& m, const std::string& what) {
    if (m.trees_per_landmark < 1 || m.trees_per_landmark > 64) invalid(what, "trees per landmark");
    if (m.tree_depth < 1 || m.tree_depth > 12) invalid(what, "tree depth");
    if (!(m.hull_padding >= 0.f && m.hull_padding < 1.f)) invalid(what, "hull padding");
    if (m.anchorCount() > 255) invalid(what, "too many hull points");
    for (auto h : m.hull_indices) {
        if (h >= kLandmarks) invalid(what, "hull index");
    }
    if (!m.mean_shape.allFinite()) invalid(what, "mean shape");
    if (m.box_priors.empty()) invalid(what, "no box prior");
    for (const auto& p : m.box_priors) {
        if (!p.shape.allFinite()) invalid(what, "box prior " + p.detector);
    }
    const auto splits = static_cast<std::size_t>(m.treesPerStage() * m.splitsPerTree());
    const auto rows = static_cast<Eigen::Index>(m.treesPerStage() * m.leavesPerTree());
    for (const auto& s : m.stages) {
        if (s.splits.size() != splits || s.regression.rows() != rows || s.row_scale.size() != std::size_t(rows)) {
            invalid(what, "stage size");
        }
        for (const auto& split : s.splits) {
            for (const FeaturePoint* p : {&split.a, &split.b}) {
                for (auto a : p->anchors) {
                    if (a >= m.anchorCount()) invalid(what, "feature anchor");
                }
                if (!std::isfinite(p->weights[0]) || !std::isfinite(p->weights[1])) invalid(what, "feature weight");
            }
        }
        for (float scale : s.row_scale) {
            if (!(scale >= 0.f && std::isfinite(scale))) invalid(what, "regression row scale");
        }
    }
}

void writeLbfModel(const std::string& path, const LbfModel& m) {
    validate(m, "landmark model for '" + path + "'");
    core::BinaryWriter w;
    w.put<std::int32_t>(m.trees_per_landmark);
    w.put<std::int32_t>(m.tree_depth);
    w.put(m.hull_padding);
    w.putVector(m.hull_indices);
    putShape(w, m.mean_shape);
    w.put<std::uint32_t>(static_cast<std::uint32_t>(m.box_priors.size()));
    for (const auto& p : m.box_priors) {
        w.putString(p.detector);
        putShape(w, p.shape);
    }
    w.put<std::uint32_t>(static_cast<std::uint32_t>(m.stages.size()));
    for (const auto& s : m.stages) {
        w.putVector(s.splits);
        // As in memory: a scale per row, then the int8 rows (version 1 had half floats).
        w.putVector(s.row_scale);
        w.putArray(s.regression.data(), static_cast<std::size_t>(s.regression.size()));
    }
    core::writeModelFile(path, kLbfMagic, kLbfVersion, w.bytes());
}

LbfModel readLbfModel(const std::string& path) {
    core::ModelFileReader file(path, kLbfMagic, 1, kLbfVersion, "landmark model");
    core::BinaryReader& r = file.reader();
    const std::uint32_t version = file.version();
    const std::string& what = file.what();
    LbfModel m;
    m.trees_per_landmark = r.get<std::int32_t>();
    m.tree_depth = r.get<std::int32_t>();
    if (m.trees_per_landmark < 1 || m.trees_per_landmark > 64 || m.tree_depth < 1 || m.tree_depth > 12) {
        r.fail("tree counts");
    }
    m.hull_padding = r.get<float>();
    m.hull_indices = r.getVector<std::uint8_t>();
    m.mean_shape = getShape(r);
    const auto priors = r.get<std::uint32_t>();
    if (priors > 16) r.fail("box prior count");
    for (std::uint32_t i = 0; i < priors; ++i) {
        BoxPrior p;
        p.detector = r.getString();
        p.shape = getShape(r);
        m.box_priors.push_back(std::move(p));
    }
    const auto stages = r.get<std::uint32_t>();
    if (stages > 64) r.fail("stage count");
    m.stages.resize(stages);
    for (auto& s : m.stages) {
        s.splits = r.getVector<Split>();
        const Eigen::Index rows = m.treesPerStage() * m.leavesPerTree();
        if (version == 1) {
            RegressionRows halfs(rows, 2 * kLandmarks);
            r.getHalfs(halfs.data(), static_cast<std::size_t>(halfs.size()));
            if (!halfs.allFinite()) r.fail("regression rows");
            s.setRegression(halfs);
        } else {
            s.row_scale = r.getVector<float>();
            s.regression.resize(rows, 2 * kLandmarks);
            r.getArray(s.regression.data(), static_cast<std::size_t>(s.regression.size()));
        }
    }
    r.expectEnd();
    validate(m, what);
    return m;
}

}  // namespace facetrack::landmarks
