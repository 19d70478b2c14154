// libFuzzer target: the iFacialMocap handshake parser (tools/send), which reads
// datagrams from anyone on the network (docs/robustness.md). It must answer
// a version (1 or 2) or nothing, and only the exact handshakes get a version.

#include "fuzz_common.hpp"

#include "send/ifacialmocap.hpp"

#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view datagram(reinterpret_cast<const char*>(data), size);
    const auto version = facetrack::send::parseIFacialMocapHandshake(datagram);
    if (version) {
        facetrack::fuzz::require(*version == 1 || *version == 2, "a handshake version other than 1 or 2");
        facetrack::fuzz::require(
            datagram.substr(0, facetrack::send::kIFacialMocapHandshake.size()) == facetrack::send::kIFacialMocapHandshake,
            "a version for a datagram that is not the handshake");
    }
    return 0;
}
