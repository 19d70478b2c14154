#include "send/sender.hpp"

#include "send/vmc.hpp"

#include "facetrack/error.hpp"

#include <algorithm>
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

std::vector<Destination> parseDestinations(const std::string& protocols, const std::string& to) {
    std::vector<Destination> out;
    const auto split = [](const std::string& text) {
        std::vector<std::string> parts;
        std::size_t start = 0;
        for (std::size_t comma; (comma = text.find(',', start)) != std::string::npos; start = comma + 1)
            parts.push_back(text.substr(start, comma - start));
        parts.push_back(text.substr(start));
        return parts;
    };
    for (const std::string& name : split(protocols)) {
        const Protocol p = parseProtocol(name);
        for (const auto& d : out)
            if (d.protocol == p) throw Error("protocol '" + name + "' given twice");
        out.push_back({p, "127.0.0.1"});
    }
    std::string host;  // for every protocol without its own
    std::vector<std::pair<std::string, std::string>> own;
    for (const std::string& part : split(to)) {
        const auto equals = part.find('=');
        if (equals != std::string::npos) {
            own.emplace_back(part.substr(0, equals), part.substr(equals + 1));
            continue;
        }
        if (!host.empty()) throw Error("--to gives two hosts for the same protocols: '" + host + "', '" + part + "'");
        if (out.size() > 1 && part.find(':') != std::string::npos)
            throw Error("--to '" + part + "': one port for several protocols; give PROTOCOL=HOST:PORT for each");
        host = part;
    }
    for (auto& d : out)
        if (!host.empty()) d.to = host;
    for (const auto& [name, where] : own) {
        const Protocol p = parseProtocol(name);
        const auto d = std::find_if(out.begin(), out.end(), [&](const Destination& x) { return x.protocol == p; });
        if (d == out.end()) throw Error("--to names '" + name + "', which --protocol does not send");
        d->to = where;
    }
    return out;
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
    switch (protocol_) {
        case Protocol::Vmc: {
            const FaceResult* face = easing_.update(frame, time_s);
            encodeVmc(face, easing_.tracking(), time_s, vmc_datagrams_);
            for (const auto& d : vmc_datagrams_) transmit(d.data(), d.size());
            break;
        }
        case Protocol::IFacialMocap: {
            listenForHandshake();
            const FaceResult* face = easing_.update(frame, time_s);
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
