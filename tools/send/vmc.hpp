#pragma once
// The VMC protocol (OSC 1.0 over UDP; protocol.vmc.info), as a Performer sends
// it to a Marionette (VSeeFace, VNyan, Warudo, VMagicMirror, EVMC4U): the face's
// blend shapes and the head and eye bones. docs/protocols.md has the bytes.

#include "facetrack/result.hpp"

#include <cstddef>
#include <vector>

namespace facetrack::send {

/// The spec's limit for one datagram: bundles are split to stay within it.
constexpr std::size_t kVmcMaxDatagram = 1500;

/// One frame as VMC datagrams, each an OSC bundle of at most kVmcMaxDatagram bytes:
///   /VMC/Ext/Root/Pos, /VMC/Ext/Bone/Pos for Neck, Head, LeftEye, RightEye
///   (local rotations in Unity's frame, rest-pose local positions), then
///   /VMC/Ext/Blend/Val for the 52 Perfect Sync shapes and the VRM presets,
///   and last /VMC/Ext/Blend/Apply, /VMC/Ext/OK (1), /VMC/Ext/T (time_s).
/// Without a face (nullptr) only OK and T are sent: the avatar holds its pose.
/// A face without pose or expression sends what it has. `out` is reused.
void encodeVmc(const FaceResult* face, double time_s, std::vector<std::vector<char>>& out);

/// The share of the head's rotation the Neck bone takes; the Head takes the rest.
constexpr float kVmcNeckShare = 1.f / 3.f;

}  // namespace facetrack::send
