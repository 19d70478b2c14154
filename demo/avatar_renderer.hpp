#pragma once
// The avatar: the face model's mesh with a face's identity and expression,
// the eyeballs turned by gaze and the head turned by its pose, drawn with
// simple two-light shading through a GLM camera. Needs a current GL context.

#include "facetrack/posed_mesh.hpp"
#include "gl.hpp"

#include "facetrack/face_model.hpp"
#include "facetrack/result.hpp"

#include <glm/glm.hpp>

#include <array>
#include <memory>
#include <optional>
#include <vector>

namespace facetrack::demo {

/// What the avatar shows: one face's result (identity, expression, rotation, gaze).
struct AvatarState {
    std::vector<float> identity;    ///< empty: the mean face
    std::vector<float> expression;  ///< native weights; empty: neutral
    /// Camera frame, as HeadPose::rotation; the default faces the camera
    /// (model +y up turns to image up, +z out of the face towards the camera).
    Quaternion rotation{0.f, 1.f, 0.f, 0.f};
    std::optional<GazeResult> gaze;  ///< camera-frame directions; none: eyes at rest

    static AvatarState of(const FaceResult& face);
};

class AvatarRenderer {
public:
    explicit AvatarRenderer(std::shared_ptr<const FaceModel> model);
    ~AvatarRenderer();
    AvatarRenderer(const AvatarRenderer&) = delete;
    AvatarRenderer& operator=(const AvatarRenderer&) = delete;

    /// Draws into the viewport (x, y, width, height) of the bound framebuffer
    /// (GL's bottom-left origin). `mirror` flips it left-right.
    void draw(const AvatarState& state, int x, int y, int width, int height, bool mirror);
    /// The same for a mesh posed already (MeshPoser::modelFrame of the face:
    /// identity, expression and eyes applied), turned by `rotation`.
    void drawMesh(const std::vector<Vec3>& mesh, const Quaternion& rotation, int x, int y, int width, int height, bool mirror);

private:
    /// The mesh draw() shows for `state`, in model-frame millimetres, before the head rotation.
    void pose(const AvatarState& state, std::vector<Vec3>& mesh) const;

    std::shared_ptr<const FaceModel> model_;
    std::array<EyeRig, 2> eyes_;
    std::vector<std::uint32_t> indices_;  // triangles drawn (not the see-through shells)
    glm::vec3 pivot_{0.f};                // the head turns about this model-frame point
    float view_distance_ = 0.f;           // mm, to frame the head
    GLuint program_ = 0, vao_ = 0, geometry_vbo_ = 0, colour_vbo_ = 0, ebo_ = 0;
    std::vector<float> geometry_;     // per vertex: position xyz, normal xyz (reused)
    std::vector<glm::vec3> normals_;  // per vertex, accumulated per frame (reused)
    std::vector<Vec3> mesh_;          // the posed mesh (reused)
};

}  // namespace facetrack::demo
