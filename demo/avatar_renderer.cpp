#include "avatar_renderer.hpp"

#include "facetrack/error.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cmath>

namespace facetrack::demo {

namespace {

const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec3 colour;
uniform mat4 model;
uniform mat4 view_projection;
out vec3 v_normal;
out vec3 v_position;
out vec3 v_colour;
void main() {
    vec4 world = model * vec4(position, 1.0);
    v_position = world.xyz;
    v_normal = mat3(model) * normal;
    v_colour = colour;
    gl_Position = view_projection * world;
}
)";

// Key light from the upper left, a dim fill from the right, ambient and a
// little Blinn-Phong specular; two-sided, since the mouth's inside shows.
const char* kFragmentShader = R"(#version 330 core
in vec3 v_normal;
in vec3 v_position;
in vec3 v_colour;
uniform vec3 eye;
out vec4 fragment;
void main() {
    vec3 n = normalize(v_normal);
    vec3 to_eye = normalize(eye - v_position);
    if (dot(n, to_eye) < 0.0) n = -n;
    vec3 key = normalize(vec3(-0.5, 0.6, 0.8));
    vec3 fill = normalize(vec3(0.7, -0.1, 0.5));
    float diffuse = 0.75 * max(dot(n, key), 0.0) + 0.25 * max(dot(n, fill), 0.0);
    float specular = 0.18 * pow(max(dot(n, normalize(key + to_eye)), 0.0), 24.0);
    vec3 c = v_colour * (0.22 + diffuse) + vec3(specular);
    fragment = vec4(pow(c, vec3(1.0 / 1.2)), 1.0);
}
)";

// ICT-FaceKit's vertex regions (its regions.json), which the shipped model
// keeps in order. Vertices past the eyeballs are see-through shells (tear
// film, eye blend, occlusion, lashes) that would hide the eyes when drawn opaque.
constexpr int kHeadEnd = 11248;  // face + head and neck: skin
constexpr int kMouthSocketEnd = 13294;
constexpr int kEyeSocketsEnd = 14062;
constexpr int kGumsEnd = 17039;
constexpr int kTeethEnd = 21451;

glm::vec3 toGlm(const Vec3& v) { return {v.x, v.y, v.z}; }

/// Distance from p to the segment [a, b].
float segmentDistance(glm::vec2 p, glm::vec2 a, glm::vec2 b) {
    const glm::vec2 ab = b - a;
    const float t = glm::clamp(glm::dot(p - a, ab) / std::max(glm::dot(ab, ab), 1e-6f), 0.f, 1.f);
    return glm::length(p - (a + t * ab));
}

/// Whether p lies inside the polygon (even-odd rule).
bool inside(glm::vec2 p, const std::vector<glm::vec2>& polygon) {
    bool in = false;
    for (std::size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
        const glm::vec2 a = polygon[i], b = polygon[j];
        if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) in = !in;
    }
    return in;
}

/// Per skin vertex of the neutral face, whether it lies on a brow (within 2.5 mm of the 300-W
/// brow line, seen from the front) or on the lips (inside the outer lip line): a bald, browless
/// head would hide a raised brow, and flat lips a pucker's shape.
enum class Feature { Skin, Brow, Lips };
std::vector<Feature> facialFeatures(const FaceModel& model, const std::vector<Vec3>& rest, glm::vec3 front) {
    const std::vector<Vec3> marks = model.landmarkPoints(rest);
    const auto flat = [](const Vec3& v) { return glm::vec2(v.x, v.y); };
    std::vector<glm::vec2> lips;
    for (int i = 48; i < 60; ++i) lips.push_back(flat(marks[static_cast<std::size_t>(i)]));
    float nearest = 1e9f;  // the brow line's depth: vertices well behind it are the head's back
    for (int i = 17; i < 27; ++i) nearest = std::min(nearest, glm::dot(toGlm(marks[static_cast<std::size_t>(i)]), front));
    std::vector<Feature> out(rest.size(), Feature::Skin);
    for (int v = 0; v < model.faceVertexCount() && v < static_cast<int>(rest.size()); ++v) {
        const glm::vec3 p = toGlm(rest[static_cast<std::size_t>(v)]);
        if (glm::dot(p, front) < nearest - 15.f) continue;
        const glm::vec2 q(p.x, p.y);
        if (inside(q, lips)) {
            out[static_cast<std::size_t>(v)] = Feature::Lips;
            continue;
        }
        for (const int start : {17, 22}) {
            for (int i = start; i < start + 4; ++i) {
                if (segmentDistance(q, flat(marks[static_cast<std::size_t>(i)]), flat(marks[static_cast<std::size_t>(i + 1)])) < 2.5f)
                    out[static_cast<std::size_t>(v)] = Feature::Brow;
            }
        }
    }
    return out;
}

}  // namespace

AvatarState AvatarState::of(const FaceResult& face) {
    AvatarState state;
    state.identity = face.identity;
    if (face.expression) state.expression = face.expression->native;
    if (face.pose) state.rotation = face.pose->rotation;
    state.gaze = face.gaze;
    return state;
}

AvatarRenderer::AvatarRenderer(std::shared_ptr<const FaceModel> model) : model_(std::move(model)), eyes_(EyeRig::both(*model_)) {
    const int n = model_->vertexCount();
    const auto left = model_->leftEyeball(), right = model_->rightEyeball();
    const int drawn_end = std::max(left.last_vertex, right.last_vertex) + 1;
    const bool ict_layout = n >= drawn_end && drawn_end == 24591;

    // Colours per vertex: skin, mouth interior, teeth, sclera, iris, pupil.
    std::vector<float> colours(static_cast<std::size_t>(n) * 3);
    const auto paint = [&](int v, glm::vec3 c) { std::copy_n(glm::value_ptr(c), 3, &colours[3 * static_cast<std::size_t>(v)]); };
    const glm::vec3 skin(0.80f, 0.62f, 0.52f);
    for (int v = 0; v < n; ++v) paint(v, skin);
    if (ict_layout) {
        for (int v = kHeadEnd; v < kMouthSocketEnd; ++v) paint(v, {0.35f, 0.12f, 0.12f});
        for (int v = kMouthSocketEnd; v < kEyeSocketsEnd; ++v) paint(v, {0.30f, 0.18f, 0.16f});
        for (int v = kEyeSocketsEnd; v < kGumsEnd; ++v) paint(v, {0.72f, 0.36f, 0.38f});
        for (int v = kGumsEnd; v < kTeethEnd; ++v) paint(v, {0.92f, 0.90f, 0.84f});
    }
    const auto rest = model_->vertices({}, {});
    if (ict_layout) {
        const std::vector<Feature> features = facialFeatures(*model_, rest,
                                                             glm::normalize(toGlm(left.optical_axis) + toGlm(right.optical_axis)));
        for (std::size_t v = 0; v < features.size(); ++v) {
            if (features[v] == Feature::Brow) paint(static_cast<int>(v), {0.30f, 0.20f, 0.14f});
            if (features[v] == Feature::Lips) paint(static_cast<int>(v), {0.72f, 0.40f, 0.40f});
        }
    }
    for (const auto& eye : {left, right}) {
        const float iris_cos = std::cos(std::asin(std::min(1.f, eye.iris_radius_mm / eye.radius_mm)));
        const float pupil_cos = std::cos(std::asin(std::min(1.f, 0.45f * eye.iris_radius_mm / eye.radius_mm)));
        const glm::vec3 centre = toGlm(eye.centre), axis = toGlm(eye.optical_axis);
        for (int v = eye.first_vertex; v <= eye.last_vertex; ++v) {
            const float c = glm::dot(glm::normalize(toGlm(rest[v]) - centre), axis);
            paint(v, c > pupil_cos ? glm::vec3(0.03f) : c > iris_cos ? glm::vec3(0.25f, 0.35f, 0.45f) : glm::vec3(0.92f, 0.92f, 0.88f));
        }
    }

    for (const auto& t : model_->triangles()) {
        if (t[0] < drawn_end && t[1] < drawn_end && t[2] < drawn_end) {
            for (int i : t) indices_.push_back(static_cast<std::uint32_t>(i));
        }
    }

    // Frame the head: turn about the centre of the face region's bounding
    // box, and stand back far enough that the head fits with a margin.
    glm::vec3 lo(1e9f), hi(-1e9f);
    for (int v = 0; v < std::min(n, kHeadEnd); ++v) {
        lo = glm::min(lo, toGlm(rest[v]));
        hi = glm::max(hi, toGlm(rest[v]));
    }
    pivot_ = 0.5f * (lo + hi);
    view_distance_ = 0.5f * glm::length(hi - lo) / std::tan(glm::radians(15.f)) * 1.05f;

    program_ = linkProgram(kVertexShader, kFragmentShader, "avatar");
    glGenVertexArrays(1, &vao_);
    glBindVertexArray(vao_);
    glGenBuffers(1, &geometry_vbo_);
    glBindBuffer(GL_ARRAY_BUFFER, geometry_vbo_);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(n * 6 * sizeof(float)), nullptr, GL_STREAM_DRAW);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), reinterpret_cast<void*>(3 * sizeof(float)));
    glEnableVertexAttribArray(0);
    glEnableVertexAttribArray(1);
    glGenBuffers(1, &colour_vbo_);
    glBindBuffer(GL_ARRAY_BUFFER, colour_vbo_);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(colours.size() * sizeof(float)), colours.data(), GL_STATIC_DRAW);
    glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
    glEnableVertexAttribArray(2);
    glGenBuffers(1, &ebo_);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo_);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices_.size() * sizeof(std::uint32_t)), indices_.data(),
                 GL_STATIC_DRAW);
    glBindVertexArray(0);
    throwOnGlError("creating the avatar mesh");
}

AvatarRenderer::~AvatarRenderer() {
    glDeleteBuffers(1, &geometry_vbo_);
    glDeleteBuffers(1, &colour_vbo_);
    glDeleteBuffers(1, &ebo_);
    glDeleteVertexArrays(1, &vao_);
    glDeleteProgram(program_);
}

void AvatarRenderer::pose(const AvatarState& state, std::vector<Vec3>& mesh) const {
    model_->vertices(state.identity, state.expression, mesh);
    if (state.gaze) {
        // Gaze is in the camera frame; the mesh is in the model frame.
        eyes_[0].turn(mesh, rotateBack(state.rotation, state.gaze->left.direction));
        eyes_[1].turn(mesh, rotateBack(state.rotation, state.gaze->right.direction));
    }
}

void AvatarRenderer::draw(const AvatarState& state, int x, int y, int width, int height, bool mirror) {
    pose(state, mesh_);
    drawMesh(mesh_, state.rotation, x, y, width, height, mirror);
}

void AvatarRenderer::drawMesh(const std::vector<Vec3>& mesh, const Quaternion& rotation, int x, int y, int width, int height, bool mirror) {
    if (mesh.size() != static_cast<std::size_t>(model_->vertexCount())) throw Error("AvatarRenderer: the mesh is not the model's");
    const std::size_t n = mesh.size();

    // Area-weighted vertex normals.
    std::vector<glm::vec3>& normals = normals_;
    normals.assign(n, glm::vec3(0.f));
    for (std::size_t i = 0; i < indices_.size(); i += 3) {
        const glm::vec3 a = toGlm(mesh[indices_[i]]), b = toGlm(mesh[indices_[i + 1]]), c = toGlm(mesh[indices_[i + 2]]);
        const glm::vec3 face_normal = glm::cross(b - a, c - a);
        for (int k = 0; k < 3; ++k) normals[indices_[i + k]] += face_normal;
    }
    geometry_.resize(n * 6);
    for (std::size_t v = 0; v < n; ++v) {
        const float len = glm::length(normals[v]);
        const glm::vec3 nv = len > 0.f ? normals[v] / len : glm::vec3(0.f, 0.f, 1.f);
        float* g = &geometry_[v * 6];
        g[0] = mesh[v].x, g[1] = mesh[v].y, g[2] = mesh[v].z;
        g[3] = nv.x, g[4] = nv.y, g[5] = nv.z;
    }

    // HeadPose::rotation maps the model frame into OpenCV's camera frame (y
    // down, z forward); GL's eye frame has y up and z backward, hence flip.
    const glm::quat q(rotation.w, rotation.x, rotation.y, rotation.z);
    const glm::mat4 camera_to_gl = glm::scale(glm::mat4(1.f), glm::vec3(1.f, -1.f, -1.f));
    const glm::mat4 model = camera_to_gl * glm::mat4_cast(glm::normalize(q)) * glm::translate(glm::mat4(1.f), -pivot_);
    const glm::vec3 eye(0.f, 0.f, view_distance_);
    const glm::mat4 view = glm::lookAt(eye, glm::vec3(0.f), glm::vec3(0.f, 1.f, 0.f));
    glm::mat4 projection = glm::perspective(glm::radians(30.f), static_cast<float>(width) / height, 0.1f * view_distance_,
                                            3.f * view_distance_);
    if (mirror) projection = glm::scale(glm::mat4(1.f), glm::vec3(-1.f, 1.f, 1.f)) * projection;
    const glm::mat4 view_projection = projection * view;

    glViewport(x, y, width, height);
    glEnable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glUseProgram(program_);
    glUniformMatrix4fv(glGetUniformLocation(program_, "model"), 1, GL_FALSE, glm::value_ptr(model));
    glUniformMatrix4fv(glGetUniformLocation(program_, "view_projection"), 1, GL_FALSE, glm::value_ptr(view_projection));
    glUniform3fv(glGetUniformLocation(program_, "eye"), 1, glm::value_ptr(eye));
    glBindVertexArray(vao_);
    glBindBuffer(GL_ARRAY_BUFFER, geometry_vbo_);
    glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(geometry_.size() * sizeof(float)), geometry_.data());
    glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(indices_.size()), GL_UNSIGNED_INT, nullptr);
    glBindVertexArray(0);
    glDisable(GL_DEPTH_TEST);
    throwOnGlError("drawing the avatar");
}

}  // namespace facetrack::demo
