#include "send/vmc.hpp"

#include "send/avatar_pose.hpp"
#include "send/shape_names.hpp"

#include <oscpack/osc/OscOutboundPacketStream.h>

#include <array>
#include <optional>
#include <string>

namespace facetrack::send {

namespace {

/// Local positions of the bones at rest on an average adult VRM avatar (metres,
/// Unity's frame), sent because receivers that apply positions would otherwise
/// collapse the bones (docs/protocols.md: turn that option off where it exists).
struct Bone {
    const char* name;
    float x, y, z;
};
constexpr Bone kNeck{"Neck", 0.f, 0.10f, -0.01f};
constexpr Bone kHead{"Head", 0.f, 0.08f, 0.01f};
constexpr Bone kLeftEye{"LeftEye", -0.032f, 0.06f, 0.05f};
constexpr Bone kRightEye{"RightEye", 0.032f, 0.06f, 0.05f};

/// Appends whole OSC messages to bundles, starting a new bundle when the next
/// message would take the current one past kVmcMaxDatagram.
class BundleWriter {
public:
    explicit BundleWriter(std::vector<std::vector<char>>& out) : out_(out) { out_.clear(); }

    template <typename Fill>
    void message(const char* address, Fill fill) {
        osc::OutboundPacketStream one(scratch_, sizeof scratch_);
        one << osc::BeginMessage(address);
        fill(one);
        one << osc::EndMessage;
        if (!bundle_ || bundle_->Size() + 4 + one.Size() > kVmcMaxDatagram) open();
        *bundle_ << osc::BeginMessage(address);
        fill(*bundle_);
        *bundle_ << osc::EndMessage;
    }

    void finish() {
        if (!bundle_) return;
        *bundle_ << osc::EndBundle;
        out_.back().resize(bundle_->Size());
        bundle_.reset();
    }

private:
    void open() {
        finish();
        out_.emplace_back(kVmcMaxDatagram);
        bundle_.emplace(out_.back().data(), out_.back().size());
        *bundle_ << osc::BeginBundleImmediate;
    }

    std::vector<std::vector<char>>& out_;
    std::optional<osc::OutboundPacketStream> bundle_;
    char scratch_[kVmcMaxDatagram];
};

void bone(BundleWriter& writer, const Bone& b, const Quaternion& unity) {
    writer.message("/VMC/Ext/Bone/Pos",
                   [&](osc::OutboundPacketStream& s) { s << b.name << b.x << b.y << b.z << unity.x << unity.y << unity.z << unity.w; });
}

void blend(BundleWriter& writer, const char* name, float value) {
    writer.message("/VMC/Ext/Blend/Val", [&](osc::OutboundPacketStream& s) { s << name << value; });
}

}  // namespace

void encodeVmc(const FaceResult* face, bool tracking, double time_s, std::vector<std::vector<char>>& out) {
    BundleWriter writer(out);
    if (face && face->pose) {
        writer.message("/VMC/Ext/Root/Pos",
                       [](osc::OutboundPacketStream& s) { s << "root" << 0.f << 0.f << 0.f << 0.f << 0.f << 0.f << 1.f; });
        const Quaternion head = headFromRest(*face->pose);
        const Quaternion neck = fraction(head, kVmcNeckShare);
        bone(writer, kNeck, toUnity(neck));
        bone(writer, kHead, toUnity(multiply({neck.w, -neck.x, -neck.y, -neck.z}, head)));
        // The user's left eye drives the avatar's left eye, as the head mirrors the user.
        const Quaternion left = face->gaze ? eyeFromRest(*face->pose, face->gaze->left) : Quaternion{};
        const Quaternion right = face->gaze ? eyeFromRest(*face->pose, face->gaze->right) : Quaternion{};
        bone(writer, kLeftEye, toUnity(left));
        bone(writer, kRightEye, toUnity(right));
    }
    if (face && face->expression) {
        static const auto names = [] {
            std::array<std::string, kArkitBlendshapeCount> n;
            for (std::size_t i = 0; i < n.size(); ++i) n[i] = perfectSyncName(arkitNames()[i]);
            return n;
        }();
        const auto& arkit = face->expression->arkit;
        for (std::size_t i = 0; i < names.size(); ++i) blend(writer, names[i].c_str(), arkit[i]);
        for (const VrmPreset& preset : vrmPresets()) blend(writer, preset.name.data(), preset.weight(arkit));
        writer.message("/VMC/Ext/Blend/Apply", [](osc::OutboundPacketStream&) {});
    }
    writer.message("/VMC/Ext/OK", [&](osc::OutboundPacketStream& s) {
        s << static_cast<osc::int32>(1) << static_cast<osc::int32>(3) << static_cast<osc::int32>(0)
          << static_cast<osc::int32>(tracking ? 1 : 0);
    });
    writer.message("/VMC/Ext/T", [&](osc::OutboundPacketStream& s) { s << static_cast<float>(time_s); });
    writer.finish();
}

}  // namespace facetrack::send
