#pragma once
/// \file
/// The linear 3D face model (converted from ICT-FaceKit by tools/train/face_model):
///   V(a, b) = neutral + sum_i a_i * identity_i + sum_j b_j * expression_j
/// in the model frame (see result.hpp). Every length this API gives is in
/// millimetres (the file stores centimetres, ICT-FaceKit's unit).
///
/// A FaceModel is data: load it once, it is immutable, and one instance can be
/// shared by any number of Trackers on any threads.

#include "facetrack/arkit.hpp"
#include "facetrack/geometry.hpp"

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace facetrack {

namespace model {
struct FaceModelData;
struct ArkitMapping;
struct LandmarkConvention;
struct Internals;
}  // namespace model

/// One eyeball of the mesh, on the mean face (millimetres, model frame).
/// Vertices [first_vertex, last_vertex] are its sclera and iris; gaze turns
/// them about `centre`, away from `optical_axis` (where the eye looks at rest).
struct EyeballGeometry {
    int first_vertex = 0;
    int last_vertex = 0;
    Vec3 centre;
    Vec3 optical_axis;
    float radius_mm = 0.f;
    float iris_radius_mm = 0.f;
};

class FaceModel {
public:
    /// Reads a model file. Throws facetrack::Error naming the file when it is
    /// missing, truncated, corrupt or of another format version.
    static std::shared_ptr<const FaceModel> load(const std::string& path);
    /// The same, with the landmark convention at `conventionPath`: where
    /// 300-W-style landmarks sit on this model (docs/expressions.md), which
    /// the fit uses in place of the model's own landmark vertices. Throws
    /// Error naming a missing or corrupt convention file.
    static std::shared_ptr<const FaceModel> load(const std::string& path, const std::string& conventionPath);

    /// The model shipped with facetrack: defaultPath(), with the shipped
    /// landmark convention when defaultConventionPath() exists.
    static std::shared_ptr<const FaceModel> loadDefault();
    /// face_model.ftm in modelDirectory() (docs/models.md says where that is).
    static std::string defaultPath();
    /// landmark_convention.ftm in modelDirectory().
    static std::string defaultConventionPath();
    /// The convention file the fit uses; empty: the model's own landmark vertices.
    const std::string& conventionPath() const;

    /// The file format version this build reads and writes.
    static std::uint32_t formatVersion();

    int vertexCount() const;
    int triangleCount() const;
    int identityCount() const;
    /// Share of the face region's identity variance the kept modes explain.
    float identityExplainedVariance() const;
    /// The model's expression names (ICT-FaceKit naming, e.g. "jawOpen", "eyeBlink_L").
    const std::vector<std::string>& expressionNames() const;
    /// Vertex index of each of the 68 iBUG landmarks.
    std::vector<int> landmarkVertices() const;
    /// The 68 landmarks on `mesh` (from vertices(); model frame, mm): each
    /// landmark vertex moved by the landmark convention's offset, i.e. where a
    /// 300-W annotator puts that landmark on this face; without a convention,
    /// the landmark vertices themselves. Throws Error when `mesh` has the wrong size.
    std::vector<Vec3> landmarkPoints(const std::vector<Vec3>& mesh) const;
    const std::string& sourcePath() const;

    /// ARKit-52 weights (arkitNames() order) from native expression weights
    /// (expressionNames() order). Throws Error when `native` has the wrong size.
    std::array<float, kArkitBlendshapeCount> toArkit(const std::vector<float>& native) const;

    /// The mesh for identity coefficients `identity` (empty: the mean face) and
    /// native expression weights `expression` (expressionNames() order; empty:
    /// neutral), in millimetres in the model frame, so that
    /// HeadPose::rotation * v + HeadPose::translation_mm is in the camera frame.
    /// Throws Error when a vector has the wrong size.
    std::vector<Vec3> vertices(const std::vector<float>& identity, const std::vector<float>& expression) const;
    /// The same into `out`, resized to vertexCount(): no allocation when it
    /// already has the capacity (reuse it frame to frame).
    void vertices(const std::vector<float>& identity, const std::vector<float>& expression, std::vector<Vec3>& out) const;
    /// The vertices `which` (indices into vertices()) alone, in that order, into `out`: a few points
    /// (a protocol's landmarks) at a small share of the whole mesh's cost. Throws Error as vertices()
    /// does, and for an index outside the mesh.
    void vertices(const std::vector<float>& identity, const std::vector<float>& expression, const std::vector<int>& which,
                  std::vector<Vec3>& out) const;

    /// The mesh's triangles, as indices into vertices().
    std::vector<std::array<int, 3>> triangles() const;
    /// Vertices [0, faceVertexCount()) are the face's skin; the rest are the
    /// back of the head, neck, eyes, mouth interior.
    int faceVertexCount() const;
    /// The subject's left (+x) and right (-x) eyeballs.
    EyeballGeometry leftEyeball() const;
    EyeballGeometry rightEyeball() const;

private:
    friend struct model::Internals;  // facetrack's own stages read the data behind it
    /// `convention` empty: none (the fit uses the model's landmark vertices as they are).
    FaceModel(std::shared_ptr<const model::FaceModelData> data, std::string source, std::string convention = {});

    std::shared_ptr<const model::FaceModelData> data_;
    std::shared_ptr<const model::LandmarkConvention> landmark_convention_;  // null without one
    std::string source_;
    std::string convention_;
    std::vector<std::string> expression_names_;
    std::shared_ptr<const model::ArkitMapping> arkit_;
    std::vector<Vec3> landmark_offsets_mm_;  // the convention's, model frame; zero without one
};

}  // namespace facetrack
