#pragma once
// iFacialMocap's UDP text protocol (an iPhone app; VSeeFace, VMagicMirror,
// Warudo and others receive it on port 49983). docs/protocols.md has the bytes.

#include "facetrack/result.hpp"

#include <optional>
#include <string>
#include <string_view>

namespace facetrack::send {

/// What a receiving app sends to the phone's port 49983 to ask for data.
constexpr std::string_view kIFacialMocapHandshake = "iFacialMocap_sahuasouryya9218sauhuiayeta91555dy3719";
constexpr int kIFacialMocapPort = 49983;

/// The handshake's version: 1 for the bare handshake, 2 when it ends in
/// "|sendDataVersion=v2"; nullopt for anything else.
std::optional<int> parseIFacialMocapHandshake(std::string_view datagram);

class IFacialMocapEncoder {
public:
    /// v1 separates name and value with '-', v2 with '&'.
    explicit IFacialMocapEncoder(int version = 1) : version_(version) {}
    void setVersion(int version) { version_ = version; }
    int version() const { return version_; }

    /// One frame:
    ///   name-value|...(52)...|=head#rx,ry,rz,px,py,pz|rightEye#rx,ry,rz|leftEye#rx,ry,rz|
    /// values 0-100, angles in degrees (rest frame, eulerXyzDeg), head
    /// position in cm from where this face was first seen. A frame that would
    /// repeat the previous one byte for byte (a receiver reads that as lost
    /// tracking) has its head roll moved by 0.01 degrees. A face without
    /// expression and pose gives "" (send nothing).
    const std::string& encode(const FaceResult& face);

private:
    int version_;
    std::string text_, previous_;
    int first_face_id_ = -1;
    Vec3 first_position_mm_;
    bool nudge_ = false;
};

}  // namespace facetrack::send
