#pragma once
// `facetrack send`'s network side: one protocol's encoder and a non-blocking
// UDP socket. send() is called once per tracked frame from the thread that
// waits on the AsyncTracker, never from the tracking thread.

#include "send/face_loss.hpp"
#include "send/ifacialmocap.hpp"
#include "send/openseeface.hpp"
#include "send/udp.hpp"

#include "facetrack/face_model.hpp"
#include "facetrack/result.hpp"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace facetrack::send {

enum class Protocol { Vmc, IFacialMocap, OpenSeeFace };

/// "vmc", "ifacialmocap" or "openseeface"; throws Error listing them otherwise.
Protocol parseProtocol(const std::string& name);
const char* protocolName(Protocol protocol);
/// The port receivers listen on by default: VMC 39539, iFacialMocap 49983, OpenSeeFace 11573.
int defaultPort(Protocol protocol);

/// One protocol and where it goes.
struct Destination {
    Protocol protocol;
    std::string to;  ///< HOST[:PORT]
};

/// `facetrack send`'s --protocol and --to: protocols comma-separated
/// ("vmc,openseeface"); `to` a comma-separated list of PROTOCOL=HOST[:PORT]
/// for single protocols and at most one HOST for the rest (each on its
/// default port), or, with one protocol, HOST[:PORT]. Throws Error on an
/// unknown or repeated protocol, a destination for a protocol not sent, or a
/// port given for several protocols at once.
std::vector<Destination> parseDestinations(const std::string& protocols, const std::string& to);

struct SenderStats {
    long frames = 0;     ///< frames handed to send()
    long datagrams = 0;  ///< datagrams the kernel took
    long bytes = 0;
    long failed = 0;  ///< datagrams not sent (no receiver, full queue): dropped, never retried
};

class Sender {
public:
    /// `to`: HOST[:PORT] (port defaulting to defaultPort). For iFacialMocap,
    /// `listenPort` (default 49983) is where a receiver's handshake is heard;
    /// after one, frames go to the handshake's sender in its version. A port
    /// already taken is reported on stderr and frames go to `to` only.
    Sender(Protocol protocol, const std::string& to, std::shared_ptr<const FaceModel> model, std::optional<int> listenPort = std::nullopt);

    /// Encodes the frame's first face (all faces for OpenSeeFace) and sends it. Never blocks.
    /// Without a face: VMC and iFacialMocap send the avatar easing to rest (FaceLossEasing),
    /// VMC with tracking status 0; OpenSeeFace sends nothing (its receivers' own sign of a lost face).
    void send(const FrameResult& frame, double time_s);
    Protocol protocol() const { return protocol_; }

    const SenderStats& stats() const { return stats_; }
    /// Where frames go now.
    std::string destination() const { return to_.describe(); }

private:
    void transmit(const void* data, std::size_t size);
    void listenForHandshake();

    Protocol protocol_;
    Endpoint to_;
    UdpSocket socket_;
    std::optional<UdpSocket> handshake_socket_;
    FaceLossEasing easing_;
    IFacialMocapEncoder ifacialmocap_;
    std::optional<OpenSeeFaceEncoder> openseeface_;
    std::vector<std::vector<char>> vmc_datagrams_;
    std::vector<std::uint8_t> osf_packet_;
    SenderStats stats_;
};

}  // namespace facetrack::send
