#include "send/sender.hpp"

#include "send/vmc.hpp"

#include "facetrack/error.hpp"

#include <chrono>
#include <cstdio>

namespace facetrack::send {

Protocol parseProtocol(const std::string& name) {
    if (name == "vmc") return Protocol::Vmc;
    if (name == "ifacialmocap") return Protocol::IFacialMocap;
    if (name == "openseeface") return Protocol::OpenSeeFace;
    throw Error("unknown protocol '" + name + "' (vmc, ifacialmocap or openseeface)");
}

const char* protocolName(Protocol protocol) {
    switch (protocol) {
        case Protocol::Vmc:
            return "vmc";
        case Protocol::IFacialMocap:
            return "ifacialmocap";
        case Protocol::OpenSeeFace:
            return "openseeface";
    }
    return "?";
}

int defaultPort(Protocol protocol) {
    switch (protocol) {
        case Protocol::Vmc:
            return 39539;
        case Protocol::IFacialMocap:
            return kIFacialMocapPort;
        case Protocol::OpenSeeFace:
            return kOpenSeeFacePort;
    }
    return 0;
}

Sender::Sender(Protocol protocol, const std::string& to, std::shared_ptr<const FaceModel> model, std::optional<int> listenPort)
    : protocol_(protocol), to_(resolveEndpoint(to, defaultPort(protocol))) {
    if (protocol == Protocol::OpenSeeFace) openseeface_.emplace(std::move(model));
    if (protocol == Protocol::IFacialMocap) {
        try {
            handshake_socket_.emplace(listenPort.value_or(kIFacialMocapPort));
        } catch (const Error& e) {
            std::fprintf(stderr, "facetrack send: %s; sending to %s without waiting for a handshake\n", e.what(), to_.describe().c_str());
        }
    }
}

void Sender::listenForHandshake() {
    if (!handshake_socket_) return;
    char buffer[256];
    Endpoint from;
    while (const std::size_t n = handshake_socket_->receive(buffer, sizeof buffer, from)) {
        if (const auto version = parseIFacialMocapHandshake(std::string_view(buffer, n))) {
            if (from.describe() != to_.describe() || *version != ifacialmocap_.version())
                std::fprintf(stderr, "facetrack send: iFacialMocap handshake (v%d) from %s\n", *version, from.describe().c_str());
            to_ = from;
            ifacialmocap_.setVersion(*version);
        }
    }
}

void Sender::transmit(const void* data, std::size_t size) {
    // Frames go out of the handshake socket when there is one: a receiver may answer only its own peer.
    UdpSocket& socket = handshake_socket_ ? *handshake_socket_ : socket_;
    if (socket.sendTo(to_, data, size)) {
        ++stats_.datagrams;
        stats_.bytes += static_cast<long>(size);
    } else {
        ++stats_.failed;
    }
}

void Sender::send(const FrameResult& frame, double time_s) {
    ++stats_.frames;
    const FaceResult* face = frame.faces.empty() ? nullptr : &frame.faces.front();
    switch (protocol_) {
        case Protocol::Vmc:
            encodeVmc(face, time_s, vmc_datagrams_);
            for (const auto& d : vmc_datagrams_) transmit(d.data(), d.size());
            break;
        case Protocol::IFacialMocap: {
            listenForHandshake();
            if (!face) break;
            const std::string& text = ifacialmocap_.encode(*face);
            if (!text.empty()) transmit(text.data(), text.size());
            break;
        }
        case Protocol::OpenSeeFace: {
            const double unix_s = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
            openseeface_->encode(frame, unix_s, osf_packet_);
            if (!osf_packet_.empty()) transmit(osf_packet_.data(), osf_packet_.size());
            break;
        }
    }
}

}  // namespace facetrack::send
