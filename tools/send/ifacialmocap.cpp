#include "send/ifacialmocap.hpp"

#include "send/avatar_pose.hpp"
#include "send/shape_names.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

namespace facetrack::send {

std::optional<int> parseIFacialMocapHandshake(std::string_view datagram) {
    while (!datagram.empty() && (datagram.back() == '\n' || datagram.back() == '\r' || datagram.back() == '\0')) datagram.remove_suffix(1);
    if (datagram == kIFacialMocapHandshake) return 1;
    if (datagram.substr(0, kIFacialMocapHandshake.size()) == kIFacialMocapHandshake &&
        datagram.substr(kIFacialMocapHandshake.size()) == "|sendDataVersion=v2")
        return 2;
    return std::nullopt;
}

namespace {
void appendAngles(std::string& out, const char* name, const Vec3& deg) {
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, "%s#%.2f,%.2f,%.2f", name, deg.x, deg.y, deg.z);
    out += buffer;
}
}  // namespace

const std::string& IFacialMocapEncoder::encode(const FaceResult& face) {
    text_.clear();
    if (!face.expression || !face.pose) return text_;
    static const auto names = [] {
        std::array<std::string, kArkitBlendshapeCount> n;
        for (std::size_t i = 0; i < n.size(); ++i) n[i] = iFacialMocapName(arkitNames()[i]);
        return n;
    }();
    const char separator = version_ == 2 ? '&' : '-';
    for (std::size_t i = 0; i < names.size(); ++i) {
        const long value = std::lround(100.f * std::clamp(face.expression->arkit[i], 0.f, 1.f));
        text_ += names[i];
        text_ += separator;
        text_ += std::to_string(value);
        text_ += '|';
    }
    const HeadPose& pose = *face.pose;
    if (face.id != first_face_id_) first_face_id_ = face.id, first_position_mm_ = pose.translation_mm;
    const Vec3 head = eulerXyzDeg(headFromRest(pose));
    // Position in the rest frame (x the subject's left, y up, z towards the camera), cm.
    const Vec3 moved{(pose.translation_mm.x - first_position_mm_.x) / 10.f, -(pose.translation_mm.y - first_position_mm_.y) / 10.f,
                     -(pose.translation_mm.z - first_position_mm_.z) / 10.f};
    const std::size_t blends = text_.size();
    for (int attempt = 0; attempt < 2; ++attempt) {
        text_.resize(blends);
        const float roll = head.z + (nudge_ ? 0.01f : 0.f);
        char buffer[160];
        std::snprintf(buffer, sizeof buffer, "=head#%.2f,%.2f,%.2f,%.3f,%.3f,%.3f|", head.x, head.y, roll, moved.x, moved.y, moved.z);
        text_ += buffer;
        const Quaternion right = face.gaze ? eyeFromRest(pose, face.gaze->right) : Quaternion{};
        const Quaternion left = face.gaze ? eyeFromRest(pose, face.gaze->left) : Quaternion{};
        appendAngles(text_, "rightEye", eulerXyzDeg(right));
        text_ += '|';
        appendAngles(text_, "leftEye", eulerXyzDeg(left));
        text_ += '|';
        if (text_ != previous_) break;
        nudge_ = !nudge_;
    }
    previous_ = text_;
    return text_;
}

}  // namespace facetrack::send
