#include "core/binary_io.hpp"
#include "model/face_model_data.hpp"

namespace facetrack::model {

namespace {

// Sizes above these mean a corrupt header field, not a real model.
constexpr std::uint64_t kMaxVertices = 10'000'000;
constexpr std::uint64_t kMaxModes = 10'000;

template <class Matrix>
void putMatrix(core::BinaryWriter& w, const Matrix& m) {
    w.put<std::uint64_t>(static_cast<std::uint64_t>(m.rows()));
    w.put<std::uint64_t>(static_cast<std::uint64_t>(m.cols()));
    w.putArray(m.data(), static_cast<std::size_t>(m.size()));
}

template <class Matrix>
Matrix getMatrix(core::BinaryReader& r, std::uint64_t maxRows, std::uint64_t maxCols) {
    const auto rows = r.get<std::uint64_t>();
    const auto cols = r.get<std::uint64_t>();
    if (rows > maxRows || cols > maxCols) r.fail("a matrix of implausible size");
    if (Matrix::RowsAtCompileTime != Eigen::Dynamic && rows != std::uint64_t(Matrix::RowsAtCompileTime)) {
        r.fail("a matrix with the wrong row count");
    }
    Matrix m(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols));
    r.getArray(m.data(), static_cast<std::size_t>(m.size()));
    return m;
}

void putEyeball(core::BinaryWriter& w, const Eyeball& e) {
    w.put(e.first_vertex);
    w.put(e.last_vertex);
    w.putArray(e.centre.data(), 3);
    w.putArray(e.optical_axis.data(), 3);
    w.put(e.radius);
    w.put(e.iris_radius);
}

Eyeball getEyeball(core::BinaryReader& r) {
    Eyeball e;
    e.first_vertex = r.get<std::uint32_t>();
    e.last_vertex = r.get<std::uint32_t>();
    r.getArray(e.centre.data(), 3);
    r.getArray(e.optical_axis.data(), 3);
    e.radius = r.get<float>();
    e.iris_radius = r.get<float>();
    return e;
}

[[noreturn]] void invalid(const std::string& what, const std::string& why) { throw Error(what + ": corrupt: " + why); }

void checkIndices(const std::vector<Triangle>& triangles, std::size_t limit, const std::string& what, const char* name) {
    for (const auto& t : triangles) {
        for (auto i : t) {
            if (i >= limit) invalid(what, std::string(name) + " index out of range");
        }
    }
}

}  // namespace

void validate(const FaceModelData& d, const std::string& what) {
    const auto v = static_cast<std::size_t>(d.neutral.cols());
    if (v == 0) invalid(what, "no vertices");
    if (d.identity_basis.rows() != static_cast<Eigen::Index>(3 * v)) invalid(what, "identity basis size");
    if (d.face_vertex_count == 0 || d.face_vertex_count > v) invalid(what, "face region size");
    for (const auto& e : d.expressions) {
        if (e.deltas.cols() != static_cast<Eigen::Index>(e.vertices.size())) invalid(what, "blendshape " + e.name);
        for (auto i : e.vertices) {
            if (i >= v) invalid(what, "blendshape " + e.name + " vertex out of range");
        }
    }
    checkIndices(d.triangles, v, what, "triangle vertex");
    if (d.triangle_uvs.size() != d.triangles.size()) invalid(what, "triangle UV count");
    checkIndices(d.triangle_uvs, static_cast<std::size_t>(d.uvs.cols()), what, "triangle UV");
    for (auto i : d.landmark_vertices) {
        if (i >= v) invalid(what, "landmark vertex out of range");
    }
    for (const auto& list : d.contour_candidates) {
        if (list.empty()) invalid(what, "empty contour candidate list");
        for (auto i : list) {
            if (i >= v) invalid(what, "contour vertex out of range");
        }
    }
    for (const Eyeball* e : {&d.left_eye, &d.right_eye}) {
        if (e->first_vertex > e->last_vertex || e->last_vertex >= v) invalid(what, "eyeball vertex range");
        if (!(e->radius > 0.f) || !(e->iris_radius > 0.f)) invalid(what, "eyeball radius");
    }
    if (!d.neutral.allFinite() || !d.identity_basis.allFinite()) invalid(what, "non-finite vertex data");
}

std::string serialize(const FaceModelData& d) {
    core::BinaryWriter w;
    putMatrix(w, d.neutral);
    w.put<std::uint64_t>(static_cast<std::uint64_t>(d.identity_basis.cols()));
    w.putHalfs(d.identity_basis.data(), static_cast<std::size_t>(d.identity_basis.size()));
    w.put(d.identity_explained_variance);
    w.put(d.face_vertex_count);

    w.put<std::uint64_t>(d.expressions.size());
    for (const auto& e : d.expressions) {
        w.putString(e.name);
        w.putVector(e.vertices);
        w.putArray(e.deltas.data(), static_cast<std::size_t>(e.deltas.size()));
    }

    w.putVector(d.triangles);
    putMatrix(w, d.uvs);
    w.putVector(d.triangle_uvs);

    w.putArray(d.landmark_vertices.data(), d.landmark_vertices.size());
    for (const auto& list : d.contour_candidates) w.putVector(list);
    putEyeball(w, d.left_eye);
    putEyeball(w, d.right_eye);
    return w.bytes();
}

FaceModelData deserialize(const std::string& payload, const std::string& what) {
    core::BinaryReader r(payload, what);
    FaceModelData d;
    d.neutral = getMatrix<Eigen::Matrix3Xf>(r, 3, kMaxVertices);
    const auto modes = r.get<std::uint64_t>();
    if (modes > kMaxModes) r.fail("identity mode count");
    d.identity_basis.resize(3 * d.neutral.cols(), static_cast<Eigen::Index>(modes));
    r.getHalfs(d.identity_basis.data(), static_cast<std::size_t>(d.identity_basis.size()));
    d.identity_explained_variance = r.get<float>();
    d.face_vertex_count = r.get<std::uint32_t>();

    const auto expressionCount = r.get<std::uint64_t>();
    if (expressionCount > kMaxModes) r.fail("expression count");
    d.expressions.resize(expressionCount);
    for (auto& e : d.expressions) {
        e.name = r.getString();
        e.vertices = r.getVector<std::uint32_t>();
        e.deltas.resize(3, static_cast<Eigen::Index>(e.vertices.size()));
        r.getArray(e.deltas.data(), static_cast<std::size_t>(e.deltas.size()));
    }

    d.triangles = r.getVector<Triangle>();
    d.uvs = getMatrix<Eigen::Matrix2Xf>(r, 2, kMaxVertices);
    d.triangle_uvs = r.getVector<Triangle>();

    r.getArray(d.landmark_vertices.data(), d.landmark_vertices.size());
    for (auto& list : d.contour_candidates) list = r.getVector<std::uint32_t>();
    d.left_eye = getEyeball(r);
    d.right_eye = getEyeball(r);
    r.expectEnd();
    validate(d, what);
    return d;
}

void writeFaceModel(const std::string& path, const FaceModelData& data) {
    validate(data, "face model for '" + path + "'");
    core::writeModelFile(path, kFaceModelMagic, kFaceModelVersion, serialize(data));
}

FaceModelData readFaceModel(const std::string& path) {
    const std::string payload = core::readModelFile(path, kFaceModelMagic, kFaceModelVersion, "face model");
    return deserialize(payload, "face model '" + path + "'");
}

}  // namespace facetrack::model
