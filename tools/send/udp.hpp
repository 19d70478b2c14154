#pragma once
// A non-blocking UDP socket: sending never waits, so a slow or dead receiver
// costs the tracker nothing (a datagram the kernel cannot queue is dropped and
// counted, as the network would drop it).

#include <netinet/in.h>

#include <cstddef>
#include <optional>
#include <string>

namespace facetrack::send {

/// An IPv4 address and port.
struct Endpoint {
    sockaddr_in address{};
    std::string describe() const;
};

/// "HOST:PORT" or "HOST" (then `defaultPort`); HOST a name or an IPv4 address.
/// Throws Error with the reason when it cannot be resolved.
Endpoint resolveEndpoint(const std::string& text, int defaultPort);

class UdpSocket {
public:
    /// Bound to `localPort` on all interfaces when given (to hear a
    /// handshake), else to an ephemeral port. Throws Error on failure.
    explicit UdpSocket(std::optional<int> localPort = std::nullopt);
    ~UdpSocket();
    UdpSocket(const UdpSocket&) = delete;
    UdpSocket& operator=(const UdpSocket&) = delete;

    /// False when the datagram was not sent (no receiver, a full queue, no
    /// route); never blocks.
    bool sendTo(const Endpoint& to, const void* data, std::size_t size);
    /// A waiting datagram, if any: its size (0: none), never blocks.
    std::size_t receive(void* data, std::size_t capacity, Endpoint& from);
    int localPort() const;

private:
    int fd_ = -1;
};

}  // namespace facetrack::send
