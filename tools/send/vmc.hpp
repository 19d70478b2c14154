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
///   and last /VMC/Ext/Blend/Apply, /VMC/Ext/OK, /VMC/Ext/T (time_s).
/// OK is V2.7's: loaded 1, calibration state 3 (calibrated), calibration mode
/// 0 (normal), tracking status 1 when `tracking`, else 0 (the face is lost and
/// `face` is the avatar easing to rest, FaceLossEasing). Without a face
/// (nullptr) only OK and T are sent. A face without pose or expression sends
/// what it has. `out` is reused.
void encodeVmc(const FaceResult* face, bool tracking, double time_s, std::vector<std::vector<char>>& out);

/// The share of the head's rotation the Neck bone takes; the Head takes the rest.
constexpr float kVmcNeckShare = 1.f / 3.f;

}  // namespace facetrack::send
