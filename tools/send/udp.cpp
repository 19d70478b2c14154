#include "send/udp.hpp"

#include "facetrack/error.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace facetrack::send {

std::string Endpoint::describe() const {
    char host[INET_ADDRSTRLEN] = {};
    inet_ntop(AF_INET, &address.sin_addr, host, sizeof host);
    return std::string(host) + ":" + std::to_string(ntohs(address.sin_port));
}

Endpoint resolveEndpoint(const std::string& text, int defaultPort) {
    std::string host = text;
    int port = defaultPort;
    const auto colon = text.rfind(':');
    if (colon != std::string::npos) {
        host = text.substr(0, colon);
        const std::string digits = text.substr(colon + 1);
        char* end = nullptr;
        const long p = std::strtol(digits.c_str(), &end, 10);
        if (digits.empty() || *end != '\0' || p < 1 || p > 65535) throw Error("'" + text + "': the port must be 1-65535");
        port = static_cast<int>(p);
    }
    if (host.empty()) throw Error("'" + text + "': no host (give HOST:PORT, e.g. 127.0.0.1:39539)");
    addrinfo hints{};
    hints.ai_family = AF_INET;
    hints.ai_socktype = SOCK_DGRAM;
    addrinfo* found = nullptr;
    if (const int rc = getaddrinfo(host.c_str(), nullptr, &hints, &found); rc != 0 || !found)
        throw Error("cannot resolve '" + host + "': " + gai_strerror(rc));
    Endpoint e;
    std::memcpy(&e.address, found->ai_addr, sizeof e.address);
    freeaddrinfo(found);
    e.address.sin_port = htons(static_cast<std::uint16_t>(port));
    return e;
}

UdpSocket::UdpSocket(std::optional<int> localPort) {
    fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd_ < 0) throw Error(std::string("cannot open a UDP socket: ") + std::strerror(errno));
    if (localPort) {
        const int yes = 1;
        setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
        sockaddr_in local{};
        local.sin_family = AF_INET;
        local.sin_addr.s_addr = htonl(INADDR_ANY);
        local.sin_port = htons(static_cast<std::uint16_t>(*localPort));
        if (::bind(fd_, reinterpret_cast<const sockaddr*>(&local), sizeof local) != 0) {
            const int err = errno;
            ::close(fd_);
            throw Error("cannot listen on UDP port " + std::to_string(*localPort) + ": " + std::strerror(err) +
                        (err == EADDRINUSE ? " (another program, perhaps a receiver, has it)" : ""));
        }
    }
}

UdpSocket::~UdpSocket() {
    if (fd_ >= 0) ::close(fd_);
}

bool UdpSocket::sendTo(const Endpoint& to, const void* data, std::size_t size) {
    const ssize_t sent = ::sendto(fd_, data, size, MSG_DONTWAIT | MSG_NOSIGNAL, reinterpret_cast<const sockaddr*>(&to.address),
                                  sizeof to.address);
    return sent == static_cast<ssize_t>(size);
}

std::size_t UdpSocket::receive(void* data, std::size_t capacity, Endpoint& from) {
    socklen_t length = sizeof from.address;
    const ssize_t got = ::recvfrom(fd_, data, capacity, MSG_DONTWAIT, reinterpret_cast<sockaddr*>(&from.address), &length);
    return got > 0 ? static_cast<std::size_t>(got) : 0;
}

int UdpSocket::localPort() const {
    sockaddr_in local{};
    socklen_t length = sizeof local;
    getsockname(fd_, reinterpret_cast<sockaddr*>(&local), &length);
    return ntohs(local.sin_port);
}

}  // namespace facetrack::send
