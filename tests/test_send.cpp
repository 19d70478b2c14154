// facetrack send's protocols, each checked by a receiver on 127.0.0.1 written
// here: names, ranges, order, sizes, and that the values are the tracker's.
// Loopback only; every receive has a timeout, so no test can hang.

#include "send/avatar_pose.hpp"
#include "send/ifacialmocap.hpp"
#include "send/openseeface.hpp"
#include "send/sender.hpp"
#include "send/shape_names.hpp"
#include "send/vmc.hpp"

#include "facetrack/facetrack.hpp"
#include "test_support.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <oscpack/osc/OscReceivedElements.h>

#include <arpa/inet.h>
#include <sys/socket.h>
#include <unistd.h>

#include <opencv2/videoio.hpp>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <thread>

namespace facetrack {
namespace {

using namespace send;

/// A UDP receiver on an ephemeral loopback port; receive() waits at most 2 s.
class Receiver {
public:
    Receiver() {
        fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a);
        socklen_t n = sizeof a;
        getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &n);
        port_ = ntohs(a.sin_port);
        timeval timeout{2, 0};
        setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
    }
    ~Receiver() { ::close(fd_); }
    int port() const { return port_; }
    std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
    /// The next datagram; empty after 2 s without one.
    std::string receive() {
        std::string d(65536, '\0');
        const ssize_t n = ::recv(fd_, d.data(), d.size(), 0);
        d.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
        return d;
    }
    void sendTo(int port, const std::string& text) {
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        a.sin_port = htons(static_cast<std::uint16_t>(port));
        ::sendto(fd_, text.data(), text.size(), 0, reinterpret_cast<sockaddr*>(&a), sizeof a);
    }
    void shortTimeout() {
        timeval timeout{0, 200000};
        setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
    }

private:
    int fd_ = -1, port_ = 0;
};

/// A free UDP port on loopback (bound and released).
int freePort() { return Receiver().port(); }

/// Tracked frames of a clip, each with a face (pose, landmarks, expression).
const std::vector<FrameResult>& trackedFrames() {
    static const std::vector<FrameResult> frames = [] {
        std::vector<FrameResult> out;
        Tracker tracker(Models::loadDefault(), {});
        const auto clip = test::clipFrames(12, "liveportrait_d3_frown_surprise.mp4");
        for (std::size_t i = 0; i < clip.size(); ++i) {
            const cv::Mat& f = clip[i];
            FrameResult r = tracker.process({f.data, f.cols, f.rows, f.step, PixelFormat::Bgr8}, i / 30.0);
            if (!r.faces.empty() && r.faces[0].pose && r.faces[0].expression) out.push_back(r);
        }
        return out;
    }();
    return frames;
}

HeadPose poseFromRest(const Eigen::Quaternionf& rest) {
    const Eigen::Quaternionf q = Eigen::Quaternionf(0, 1, 0, 0) * rest;
    HeadPose p;
    p.rotation = {q.w(), q.x(), q.y(), q.z()};
    p.translation_mm = {10, -20, 600};
    return p;
}

Eigen::Quaternionf eigen(const Quaternion& q) { return {q.w, q.x, q.y, q.z}; }

// --- conversions ----------------------------------------------------------

TEST(AvatarPose, FrontalIsIdentityAndTurningLeftTurnsTheAvatarLeft) {
    const Quaternion frontal = headFromRest(poseFromRest(Eigen::Quaternionf::Identity()));
    EXPECT_NEAR(std::fabs(frontal.w), 1.f, 1e-6f);
    // Subject turns 20 degrees to their left: about +y in the rest frame.
    const Eigen::Quaternionf left(Eigen::AngleAxisf(20.f * 3.14159265f / 180.f, Eigen::Vector3f::UnitY()));
    const Quaternion rest = headFromRest(poseFromRest(left));
    EXPECT_TRUE(eigen(rest).isApprox(left, 1e-5f));
    const Vec3 euler = eulerXyzDeg(rest);
    EXPECT_NEAR(euler.y, 20.f, 1e-3f);
    EXPECT_NEAR(euler.x, 0.f, 1e-3f);
    // In Unity (left-handed, +x the avatar's right) the avatar's forward turns to -x: its own left.
    const Quaternion unity = toUnity(rest);
    const Eigen::Vector3f forward = eigen(unity).toRotationMatrix() * Eigen::Vector3f::UnitZ();
    // Unity's rotation matrices act as right-handed ones on the reflected axes: x flips sign.
    EXPECT_LT(forward.x(), -0.3f);
    // Looking down: x > 0.
    const Eigen::Quaternionf down(Eigen::AngleAxisf(0.3f, Eigen::Vector3f::UnitX()));
    EXPECT_NEAR(eulerXyzDeg(headFromRest(poseFromRest(down))).x, 0.3f * 57.2957795f, 1e-3f);
}

TEST(AvatarPose, EyeRotationFollowsTheGazeInTheHeadFrame) {
    const Eigen::Quaternionf turned(Eigen::AngleAxisf(0.4f, Eigen::Vector3f::UnitY()));
    const HeadPose pose = poseFromRest(turned);
    // Gaze straight out of the face: no eye rotation, whatever the head does.
    const Eigen::Vector3f out = eigen(pose.rotation) * Eigen::Vector3f::UnitZ();
    EyeGaze eye;
    eye.direction = {out.x(), out.y(), out.z()};
    EXPECT_NEAR(std::fabs(eyeFromRest(pose, eye).w), 1.f, 1e-5f);
    // Gaze 10 degrees up in the head frame: a 10-degree rotation of the eye.
    const Eigen::Vector3f up = eigen(pose.rotation) * Eigen::Vector3f(0, std::sin(0.1745f), std::cos(0.1745f));
    eye.direction = {up.x(), up.y(), up.z()};
    EXPECT_NEAR(2.f * std::acos(std::fabs(eyeFromRest(pose, eye).w)), 0.1745f, 1e-3f);
    eye.direction = {NAN, 0, 1};
    EXPECT_NEAR(eyeFromRest(pose, eye).w, 1.f, 1e-6f);
}

TEST(ShapeNames, PerfectSyncIFacialMocapAndVrmNames) {
    EXPECT_EQ(perfectSyncName("jawOpen"), "JawOpen");
    EXPECT_EQ(perfectSyncName("eyeBlinkLeft"), "EyeBlinkLeft");
    EXPECT_EQ(iFacialMocapName("eyeBlinkLeft"), "eyeBlink_L");
    EXPECT_EQ(iFacialMocapName("mouthSmileRight"), "mouthSmile_R");
    EXPECT_EQ(iFacialMocapName("jawLeft"), "jawLeft");
    EXPECT_EQ(iFacialMocapName("mouthRight"), "mouthRight");
    EXPECT_EQ(iFacialMocapName("browInnerUp"), "browInnerUp");
    std::array<float, kArkitBlendshapeCount> arkit{};
    arkit[static_cast<std::size_t>(arkitIndex("eyeBlinkLeft"))] = 0.8f;
    arkit[static_cast<std::size_t>(arkitIndex("jawOpen"))] = 0.6f;
    for (const VrmPreset& p : vrmPresets()) {
        const float v = p.weight(arkit);
        EXPECT_GE(v, 0.f) << p.name;
        EXPECT_LE(v, 1.f) << p.name;
        if (p.name == "Blink_L") {
            EXPECT_FLOAT_EQ(v, 0.8f);
        } else if (p.name == "Blink_R") {
            EXPECT_FLOAT_EQ(v, 0.f);
        } else if (p.name == "A") {
            EXPECT_FLOAT_EQ(v, 0.6f);
        }
    }
}

// --- VMC ------------------------------------------------------------------

struct OscMessage {
    std::string address;
    std::string types;
    std::vector<std::string> strings;
    std::vector<float> floats;
    std::vector<int> ints;
};

std::vector<OscMessage> decodeBundle(const std::string& datagram) {
    std::vector<OscMessage> out;
    osc::ReceivedPacket packet(datagram.data(), static_cast<osc::osc_bundle_element_size_t>(datagram.size()));
    EXPECT_TRUE(packet.IsBundle());
    osc::ReceivedBundle bundle(packet);
    for (auto e = bundle.ElementsBegin(); e != bundle.ElementsEnd(); ++e) {
        EXPECT_TRUE(e->IsMessage());
        osc::ReceivedMessage m(*e);
        OscMessage msg;
        msg.address = m.AddressPattern();
        msg.types = m.TypeTags() ? m.TypeTags() : "";
        for (auto a = m.ArgumentsBegin(); a != m.ArgumentsEnd(); ++a) {
            if (a->IsString()) msg.strings.push_back(a->AsString());
            if (a->IsFloat()) msg.floats.push_back(a->AsFloat());
            if (a->IsInt32()) msg.ints.push_back(a->AsInt32());
        }
        out.push_back(msg);
    }
    return out;
}

TEST(Vmc, AFrameIsBundlesWithinTheLimitBonesThenBlendsThenApplyOkAndTime) {
    FACETRACK_REQUIRE_SHARED();
    Receiver receiver;
    Sender sender(Protocol::Vmc, receiver.address(), nullptr);
    ASSERT_GE(trackedFrames().size(), 10u);
    for (std::size_t f = 0; f < 3; ++f) {
        const FrameResult& frame = trackedFrames()[f];
        const FaceResult& face = frame.faces[0];
        const long before = sender.stats().datagrams;
        sender.send(frame, 0.5 + static_cast<double>(f));
        const long datagrams = sender.stats().datagrams - before;
        ASSERT_GE(datagrams, 2) << "52 + 14 blend values need more than one 1500-byte bundle";
        std::vector<OscMessage> messages;
        for (long d = 0; d < datagrams; ++d) {
            const std::string datagram = receiver.receive();
            ASSERT_FALSE(datagram.empty());
            EXPECT_LE(datagram.size(), kVmcMaxDatagram);
            EXPECT_EQ(datagram.substr(0, 8), std::string("#bundle\0", 8));
            for (const auto& m : decodeBundle(datagram)) messages.push_back(m);
        }
        ASSERT_EQ(messages.size(), 1u + 4u + 52u + vrmPresets().size() + 3u);
        EXPECT_EQ(messages[0].address, "/VMC/Ext/Root/Pos");
        EXPECT_EQ(messages[0].types, "sfffffff");
        const char* bones[] = {"Neck", "Head", "LeftEye", "RightEye"};
        Eigen::Quaternionf composed = Eigen::Quaternionf::Identity();
        for (int b = 0; b < 4; ++b) {
            const OscMessage& m = messages[1 + static_cast<std::size_t>(b)];
            EXPECT_EQ(m.address, "/VMC/Ext/Bone/Pos");
            ASSERT_EQ(m.strings.size(), 1u);
            EXPECT_EQ(m.strings[0], bones[b]);
            ASSERT_EQ(m.floats.size(), 7u);
            const Eigen::Quaternionf q(m.floats[6], m.floats[3], m.floats[4], m.floats[5]);
            EXPECT_NEAR(q.norm(), 1.f, 1e-4f);
            if (b < 2) composed = composed * q;
        }
        // Neck then Head: together the whole head rotation, in Unity's frame.
        EXPECT_TRUE(composed.isApprox(eigen(toUnity(headFromRest(*face.pose))), 1e-4f) ||
                    composed.isApprox(Eigen::Quaternionf(-eigen(toUnity(headFromRest(*face.pose))).coeffs()), 1e-4f));
        for (int i = 0; i < 52; ++i) {
            const OscMessage& m = messages[5 + static_cast<std::size_t>(i)];
            EXPECT_EQ(m.address, "/VMC/Ext/Blend/Val");
            EXPECT_EQ(m.types, "sf");
            EXPECT_EQ(m.strings.at(0), perfectSyncName(arkitNames()[static_cast<std::size_t>(i)]));
            EXPECT_EQ(m.floats.at(0), face.expression->arkit[static_cast<std::size_t>(i)]);
        }
        for (std::size_t i = 0; i < vrmPresets().size(); ++i) {
            const OscMessage& m = messages[57 + i];
            EXPECT_EQ(m.strings.at(0), vrmPresets()[i].name);
            EXPECT_EQ(m.floats.at(0), vrmPresets()[i].weight(face.expression->arkit));
        }
        const std::size_t n = messages.size();
        EXPECT_EQ(messages[n - 3].address, "/VMC/Ext/Blend/Apply");
        EXPECT_EQ(messages[n - 3].types, "");
        EXPECT_EQ(messages[n - 2].address, "/VMC/Ext/OK");
        EXPECT_EQ(messages[n - 2].ints, (std::vector<int>{1, 3, 0, 1}));  // loaded, calibrated, normal mode, tracking
        EXPECT_EQ(messages[n - 1].address, "/VMC/Ext/T");
        EXPECT_EQ(messages[n - 1].floats, std::vector<float>{0.5f + static_cast<float>(f)});
    }
}

TEST(Vmc, BytesFollowOsc10) {
    // /VMC/Ext/OK with ints 1 3 0 0: address padded to 4, type tag ",iiii" padded, big-endian ints.
    FaceResult none;
    std::vector<std::vector<char>> datagrams;
    encodeVmc(nullptr, false, 2.0, datagrams);
    ASSERT_EQ(datagrams.size(), 1u);
    const std::string d(datagrams[0].begin(), datagrams[0].end());
    const std::string ok = std::string("/VMC/Ext/OK\0,iiii\0\0\0\0\0\0\x01\0\0\0\x03\0\0\0\0\0\0\0\0", 36);
    EXPECT_NE(d.find(ok), std::string::npos);
    // 2.0f big-endian is 40 00 00 00, after "/VMC/Ext/T\0\0" ",f\0\0".
    EXPECT_NE(d.find(std::string("/VMC/Ext/T\0\0,f\0\0\x40\0\0\0", 20)), std::string::npos);
    // The Apply message has no arguments but still its type tag ",".
    none.expression = ExpressionResult{};
    encodeVmc(&none, true, 0.0, datagrams);
    std::string all;
    for (const auto& g : datagrams) all.append(g.begin(), g.end());
    EXPECT_NE(all.find(std::string("/VMC/Ext/Blend/Apply\0\0\0\0,\0\0\0", 28)), std::string::npos);
    EXPECT_EQ(all.find("/VMC/Ext/Bone/Pos"), std::string::npos);  // no pose, no bones
}

// --- iFacialMocap ---------------------------------------------------------

struct IfmFrame {
    std::vector<std::pair<std::string, int>> shapes;
    std::vector<float> head, rightEye, leftEye;
};

IfmFrame parseIfm(const std::string& text, char separator) {
    IfmFrame f;
    std::stringstream s(text);
    std::string part;
    const auto numbers = [](const std::string& list) {
        std::vector<float> v;
        std::stringstream l(list);
        std::string x;
        while (std::getline(l, x, ',')) v.push_back(std::stof(x));
        return v;
    };
    while (std::getline(s, part, '|')) {
        if (part.rfind("=head#", 0) == 0) f.head = numbers(part.substr(6));
        else if (part.rfind("rightEye#", 0) == 0) f.rightEye = numbers(part.substr(9));
        else if (part.rfind("leftEye#", 0) == 0) f.leftEye = numbers(part.substr(8));
        else {
            const auto at = part.rfind(separator);
            EXPECT_NE(at, std::string::npos) << part;
            if (at == std::string::npos) continue;
            f.shapes.emplace_back(part.substr(0, at), std::stoi(part.substr(at + 1)));
        }
    }
    return f;
}

TEST(IFacialMocap, HandshakeVersions) {
    EXPECT_EQ(parseIFacialMocapHandshake(kIFacialMocapHandshake), 1);
    EXPECT_EQ(parseIFacialMocapHandshake(std::string(kIFacialMocapHandshake) + "|sendDataVersion=v2"), 2);
    EXPECT_EQ(parseIFacialMocapHandshake(std::string(kIFacialMocapHandshake) + "\n"), 1);
    EXPECT_FALSE(parseIFacialMocapHandshake("hello"));
    EXPECT_FALSE(parseIFacialMocapHandshake(std::string(kIFacialMocapHandshake) + "|sendDataVersion=v9"));
}

TEST(IFacialMocap, AnswersTheHandshakeAndSendsTheTrackersValues) {
    FACETRACK_REQUIRE_SHARED();
    Receiver app;
    Receiver elsewhere;  // the --to address: unused once a handshake names the app
    const int listen = freePort();
    Sender sender(Protocol::IFacialMocap, elsewhere.address(), nullptr, listen);
    app.sendTo(listen, std::string(kIFacialMocapHandshake) + "|sendDataVersion=v2");
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    for (std::size_t f = 0; f < 4; ++f) {
        const FaceResult& face = trackedFrames()[f].faces[0];
        sender.send(trackedFrames()[f], 0.0);
        const std::string text = app.receive();
        ASSERT_FALSE(text.empty());
        const IfmFrame got = parseIfm(text, '&');
        ASSERT_EQ(got.shapes.size(), 52u);
        for (std::size_t i = 0; i < 52; ++i) {
            EXPECT_EQ(got.shapes[i].first, iFacialMocapName(arkitNames()[i]));
            EXPECT_EQ(got.shapes[i].second, std::lround(100.f * face.expression->arkit[i]));
            EXPECT_GE(got.shapes[i].second, 0);
            EXPECT_LE(got.shapes[i].second, 100);
        }
        ASSERT_EQ(got.head.size(), 6u);
        const Vec3 euler = eulerXyzDeg(headFromRest(*face.pose));
        EXPECT_NEAR(got.head[0], euler.x, 0.006f);
        EXPECT_NEAR(got.head[1], euler.y, 0.006f);
        EXPECT_NEAR(got.head[2], euler.z, 0.02f);
        EXPECT_EQ(got.rightEye.size(), 3u);
        EXPECT_EQ(got.leftEye.size(), 3u);
    }
    elsewhere.shortTimeout();
    EXPECT_TRUE(elsewhere.receive().empty());
}

TEST(IFacialMocap, WithoutAHandshakeSendsToTheGivenAddressAndNeverRepeatsAFrame) {
    FACETRACK_REQUIRE_SHARED();
    Receiver app;
    Sender sender(Protocol::IFacialMocap, app.address(), nullptr, freePort());
    const FrameResult& frame = trackedFrames()[0];
    std::string previous;
    for (int i = 0; i < 4; ++i) {
        sender.send(frame, 0.0);  // the same frame four times
        const std::string text = app.receive();
        ASSERT_FALSE(text.empty());
        EXPECT_NE(text, previous);
        EXPECT_EQ(parseIfm(text, '-').shapes.size(), 52u);  // v1 separator
        previous = text;
    }
    // No face: the avatar eases to rest, and holds there.
    sender.send(FrameResult{}, 1.0);
    EXPECT_FALSE(app.receive().empty());
    sender.send(FrameResult{}, 1.0 + kFaceLossEaseSeconds);
    const IfmFrame rest = parseIfm(app.receive(), '-');
    ASSERT_EQ(rest.shapes.size(), 52u);
    for (const auto& [name, value] : rest.shapes) EXPECT_EQ(value, 0) << name;
}

// --- OpenSeeFace ----------------------------------------------------------

template <typename T>
T read(const std::string& d, std::size_t& at) {
    T v;
    std::memcpy(&v, d.data() + at, sizeof v);
    at += sizeof v;
    return v;
}

TEST(OpenSeeFace, PacketLayoutAndValuesMatchTheTracker) {
    FACETRACK_REQUIRE_SHARED();
    Receiver receiver;
    Sender sender(Protocol::OpenSeeFace, receiver.address(), FaceModel::loadDefault());
    double lastTime = 0;
    for (std::size_t f = 0; f < 3; ++f) {
        const FrameResult& frame = trackedFrames()[f];
        const FaceResult& face = frame.faces[0];
        sender.send(frame, 0.0);
        const std::string d = receiver.receive();
        ASSERT_EQ(d.size(), kOpenSeeFaceFaceBytes);
        std::size_t at = 0;
        const double time = read<double>(d, at);
        EXPECT_GT(time, lastTime);
        lastTime = time;
        EXPECT_EQ(read<std::int32_t>(d, at), face.id);
        EXPECT_EQ(read<float>(d, at), static_cast<float>(frame.camera.width));
        EXPECT_EQ(read<float>(d, at), static_cast<float>(frame.camera.height));
        // Eye openness: the gaze stage's, else 1 - eyeBlink.
        const float rightOpen = read<float>(d, at), leftOpen = read<float>(d, at);
        const auto blink = [&](const char* name) { return face.expression->arkit[static_cast<std::size_t>(arkitIndex(name))]; };
        EXPECT_FLOAT_EQ(rightOpen, face.gaze ? face.gaze->right.openness : 1.f - blink("eyeBlinkRight"));
        EXPECT_FLOAT_EQ(leftOpen, face.gaze ? face.gaze->left.openness : 1.f - blink("eyeBlinkLeft"));
        EXPECT_EQ(read<std::uint8_t>(d, at), 1);
        EXPECT_GE(read<float>(d, at), 0.f);
        const float qx = read<float>(d, at), qy = read<float>(d, at), qz = read<float>(d, at), qw = read<float>(d, at);
        const Eigen::Matrix3f osf = Eigen::Quaternionf(qw, qx, qy, qz).toRotationMatrix();
        // Undo OpenSeeFace's axes: P R diag(-1, 1, 1) = osf.
        Eigen::Matrix3f swap;
        swap << 0, 1, 0, 1, 0, 0, 0, 0, 1;
        const Eigen::Matrix3f ours = swap * osf * Eigen::Vector3f(-1, 1, 1).asDiagonal();
        EXPECT_TRUE(ours.isApprox(eigen(face.pose->rotation).normalized().toRotationMatrix(), 1e-4f));
        // The Euler angles are RQDecomp3x3's of that matrix: near (180, 0, -90) for a face near frontal.
        const float ex = read<float>(d, at), ey = read<float>(d, at), ez = read<float>(d, at);
        EXPECT_GT(std::fabs(ex), 140.f);
        EXPECT_LT(std::fabs(ey), 40.f);
        EXPECT_NEAR(ez, -90.f, 40.f);
        const float tx = read<float>(d, at), ty = read<float>(d, at), tz = read<float>(d, at);
        EXPECT_NEAR(tx * kOpenSeeFaceUnitMm, face.pose->translation_mm.y, 1e-2f);
        EXPECT_NEAR(ty * kOpenSeeFaceUnitMm, face.pose->translation_mm.x, 1e-2f);
        EXPECT_NEAR(tz * kOpenSeeFaceUnitMm, face.pose->translation_mm.z, 1e-2f);
        for (int i = 0; i < 66; ++i) EXPECT_EQ(read<float>(d, at), face.confidence);
        EXPECT_EQ(read<float>(d, at), face.gaze ? face.gaze->right.openness : 0.f);
        EXPECT_EQ(read<float>(d, at), face.gaze ? face.gaze->left.openness : 0.f);
        for (int i = 0; i < 66; ++i) {
            const Point2 p = (*face.landmarks)[static_cast<std::size_t>(kOpenSeeFaceFromIbug[static_cast<std::size_t>(i)])];
            EXPECT_EQ(read<float>(d, at), p.x);
            EXPECT_EQ(read<float>(d, at), p.y);
        }
        if (face.gaze) {  // the pupils, right then left
            EXPECT_EQ(read<float>(d, at), face.gaze->right.pupil_px.x);
            EXPECT_EQ(read<float>(d, at), face.gaze->right.pupil_px.y);
            EXPECT_EQ(read<float>(d, at), face.gaze->left.pupil_px.x);
            EXPECT_EQ(read<float>(d, at), face.gaze->left.pupil_px.y);
        } else {
            at += 2 * 2 * sizeof(float);
        }
        std::vector<Eigen::Vector3f> points(70);
        for (auto& p : points) p = {read<float>(d, at), read<float>(d, at), read<float>(d, at)};
        EXPECT_LT(points[30].head<2>().norm(), 1e-5f);  // the nose tip at x = y = 0
        // OpenSeeFace's x is the subject's right, written as is: point 0 (right jaw) at x > 0.
        EXPECT_GT(points[0].x(), 0.2f);
        EXPECT_LT(points[16].x(), -0.2f);
        // Written (x, -y, -z): the brows (up) have y < 0.
        EXPECT_LT(points[19].y(), 0.f);
        at += 14 * sizeof(float);
        EXPECT_EQ(at, kOpenSeeFaceFaceBytes);
    }
}

TEST(OpenSeeFace, FacesAreConcatenatedAndNoFaceSendsNothing) {
    FACETRACK_REQUIRE_SHARED();
    OpenSeeFaceEncoder encoder(FaceModel::loadDefault());
    FrameResult two = trackedFrames()[0];
    two.faces.push_back(two.faces[0]);
    two.faces[1].id = 7;
    std::vector<std::uint8_t> packet;
    encoder.encode(two, 1.0, packet);
    ASSERT_EQ(packet.size(), 2 * kOpenSeeFaceFaceBytes);
    std::int32_t id;
    std::memcpy(&id, packet.data() + kOpenSeeFaceFaceBytes + 8, 4);
    EXPECT_EQ(id, 7);
    encoder.encode(FrameResult{}, 1.0, packet);
    EXPECT_TRUE(packet.empty());
    EXPECT_THROW(OpenSeeFaceEncoder(nullptr), Error);
}

// --- the sender and the command -------------------------------------------

TEST(Sender, ADeadReceiverCostsNothingAndBadAddressesAreClearErrors) {
    FACETRACK_REQUIRE_SHARED();
    Sender sender(Protocol::Vmc, "127.0.0.1:" + std::to_string(freePort()), nullptr);
    for (int i = 0; i < 100; ++i) sender.send(trackedFrames()[static_cast<std::size_t>(i) % trackedFrames().size()], i / 30.0);
    EXPECT_EQ(sender.stats().frames, 100);
    EXPECT_THROW(Sender(Protocol::Vmc, "127.0.0.1:99999", nullptr), Error);
    EXPECT_THROW(Sender(Protocol::Vmc, ":39539", nullptr), Error);
    EXPECT_THROW(Sender(Protocol::Vmc, "no-such-host.invalid:1", nullptr), Error);
    EXPECT_THROW(parseProtocol("osc"), Error);
}

TEST(SendCommand, StreamsAClipToAReceiver) {
    FACETRACK_REQUIRE_SHARED();
    Receiver receiver;
    const test::CommandRun run = test::runCommand(
        FACETRACK_CLI, "send --input '" + test::sharedDir() +
                           "/data/clips/liveportrait_d3_frown_surprise.mp4' --protocol openseeface --to " + receiver.address() +
                           " --frames 8 --fast");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_NE(run.err.find("8 frames sent"), std::string::npos) << run.err;
    EXPECT_NE(run.err.find("capture to sent p50"), std::string::npos) << run.err;
    int packets = 0;
    receiver.shortTimeout();
    for (std::string d = receiver.receive(); !d.empty(); d = receiver.receive()) {
        EXPECT_EQ(d.size() % kOpenSeeFaceFaceBytes, 0u);
        ++packets;
    }
    EXPECT_GE(packets, 7);  // every frame with a face
    const test::CommandRun bad = test::runCommand(FACETRACK_CLI, "send --input x.mp4 --protocol carrier-pigeon");
    EXPECT_EQ(bad.exit_code, 1);
    EXPECT_NE(bad.err.find("unknown protocol 'carrier-pigeon'"), std::string::npos) << bad.err;
}

// --- several protocols, a lost face ---------------------------------------

TEST(Destinations, OneHostForAllOrOnePerProtocol) {
    auto d = parseDestinations("vmc", "");
    ASSERT_EQ(d.size(), 1u);
    EXPECT_EQ(d[0].to, "127.0.0.1");
    d = parseDestinations("vmc", "10.0.0.2:39540");
    EXPECT_EQ(d[0].to, "10.0.0.2:39540");
    d = parseDestinations("vmc,ifacialmocap,openseeface", "10.0.0.2,openseeface=10.0.0.3:11600");
    ASSERT_EQ(d.size(), 3u);
    EXPECT_EQ(d[0].protocol, Protocol::Vmc);
    EXPECT_EQ(d[0].to, "10.0.0.2");
    EXPECT_EQ(d[1].to, "10.0.0.2");
    EXPECT_EQ(d[2].protocol, Protocol::OpenSeeFace);
    EXPECT_EQ(d[2].to, "10.0.0.3:11600");
    const auto says = [](const char* protocols, const char* to, const char* what) {
        try {
            parseDestinations(protocols, to);
            ADD_FAILURE() << protocols << " / " << to << " accepted";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    };
    says("vmc,vmc", "", "given twice");
    says("vmc,osc", "", "unknown protocol 'osc'");
    says("vmc,openseeface", "127.0.0.1:5000", "one port for several protocols");
    says("vmc", "ifacialmocap=127.0.0.1", "which --protocol does not send");
    says("vmc", "a,b", "two hosts");
}

/// A frame whose one face smiles `smile`, turned `yawDeg` about the camera's y axis, eyes at `openness`.
FrameResult faceFrame(float smile, float yawDeg, float openness) {
    FrameResult frame;
    FaceResult& face = frame.faces.emplace_back();
    face.expression.emplace();
    face.expression->arkit[static_cast<std::size_t>(arkitIndex("mouthSmileLeft"))] = smile;
    face.expression->native.assign(5, smile);
    const Eigen::Quaternionf q = Eigen::Quaternionf(
                                     Eigen::AngleAxisf(yawDeg * static_cast<float>(M_PI) / 180.f, Eigen::Vector3f::UnitY())) *
                                 Eigen::Quaternionf(0, 1, 0, 0);
    face.pose = poseFromRest(Eigen::Quaternionf::Identity());
    face.pose->rotation = {q.w(), q.x(), q.y(), q.z()};
    face.pose->euler_deg = {0.f, yawDeg, 0.f};
    face.gaze.emplace();
    face.gaze->left.openness = face.gaze->right.openness = openness;
    face.gaze->left.direction = face.gaze->right.direction = {0.f, 0.f, -1.f};
    return frame;
}

float angleFromFrontalDeg(const Quaternion& q) {
    return eigen(q).angularDistance(Eigen::Quaternionf(0, 1, 0, 0)) * 180.f / static_cast<float>(M_PI);
}

// Lost: from the last face to rest in 0.5 s, then held; found: eased in over 0.5 s, then the face as tracked.
TEST(FaceLossEasing, RelaxesALostFaceThenEasesTheReturningFaceIn) {
    FaceLossEasing easing;
    const std::size_t smile = static_cast<std::size_t>(arkitIndex("mouthSmileLeft"));
    EXPECT_EQ(easing.update(FrameResult{}, 0.0), nullptr);  // nothing seen yet
    const FrameResult tracked = faceFrame(0.8f, 30.f, 0.2f);
    double t = 1.0;
    const FaceResult* out = easing.update(tracked, t);
    ASSERT_NE(out, nullptr);
    EXPECT_TRUE(easing.tracking());
    EXPECT_EQ(out->expression->arkit[smile], 0.8f);  // the first face as it is
    float lastSmile = 0.8f, lastTurn = 30.f;
    for (int f = 1; f <= 20; ++f) {  // lost, at 30 fps
        t = 1.0 + f / 30.0;
        out = easing.update(FrameResult{}, t);
        ASSERT_NE(out, nullptr);
        EXPECT_FALSE(easing.tracking());
        const float w = out->expression->arkit[smile], turn = angleFromFrontalDeg(out->pose->rotation);
        EXPECT_LE(w, lastSmile);
        EXPECT_LE(turn, lastTurn + 1e-3f);
        if (f == 1) {
            EXPECT_GT(w, 0.75f);  // a smooth start, not a jump
        }
        if (t - (1.0 + 1 / 30.0) >= kFaceLossEaseSeconds - 1e-9) {  // since the first frame without the face
            EXPECT_EQ(w, 0.f) << "at " << t - 1.0 << " s";
            EXPECT_LT(turn, 0.01f);
            EXPECT_EQ(out->gaze->left.openness, 1.f);
            EXPECT_EQ(out->pose->translation_mm.z, 600.f);  // where the head was
        }
        lastSmile = w;
        lastTurn = turn;
    }
    // Found again: eased in from rest, then exactly the tracked face.
    t += 1.0 / 30.0;
    out = easing.update(tracked, t);
    EXPECT_TRUE(easing.tracking());
    EXPECT_LT(out->expression->arkit[smile], 0.1f);
    out = easing.update(tracked, t + 0.25);
    EXPECT_NEAR(out->expression->arkit[smile], 0.4f, 0.01f);  // half way at half the time
    out = easing.update(tracked, t + 0.5);
    EXPECT_EQ(out->expression->arkit[smile], 0.8f);
    EXPECT_EQ(out->pose->rotation.w, tracked.faces[0].pose->rotation.w);
    // The matrices follow the eased rotation.
    out = easing.update(FrameResult{}, t + 0.6);
    out = easing.update(FrameResult{}, t + 0.8);
    EXPECT_NEAR(out->pose->camera_from_model[0],
                1.f - 2.f * (out->pose->rotation.y * out->pose->rotation.y + out->pose->rotation.z * out->pose->rotation.z), 1e-5f);
    EXPECT_EQ(out->pose->gl_model_view[13], -out->pose->camera_from_model[13]);
}

/// Every datagram a Receiver gets while it runs, on a thread of its own (a run
/// of the CLI would fill the socket's buffer before the test could read it).
class Collector {
public:
    Collector() {
        receiver_.shortTimeout();
        thread_ = std::thread([this] {
            while (!stop_) {
                std::string d = receiver_.receive();
                if (!d.empty()) datagrams_.push_back(std::move(d));
            }
        });
    }
    ~Collector() { finish(); }
    std::string address() const { return receiver_.address(); }
    /// Waits for the stragglers and stops.
    const std::vector<std::string>& finish() {
        if (thread_.joinable()) {
            std::this_thread::sleep_for(std::chrono::milliseconds(300));
            stop_ = true;
            thread_.join();
        }
        return datagrams_;
    }

private:
    Receiver receiver_;
    std::atomic<bool> stop_{false};
    std::vector<std::string> datagrams_;
    std::thread thread_;
};

// One run sends VMC, iFacialMocap and OpenSeeFace at once; the face leaves the
// frame after 30 frames: VMC's tracking status drops to 0 on the first frame
// without it and the avatar's weights are at rest within 0.6 s.
TEST(SendCommand, ThreeProtocolsAtOnceAndAFaceThatLeaves) {
    FACETRACK_REQUIRE_SHARED();
    const std::string clip = ::testing::TempDir() + "facetrack_face_leaves.avi";
    {
        cv::VideoWriter writer(clip, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 30.0, cv::Size(400, 300));
        ASSERT_TRUE(writer.isOpened());
        const auto frames = test::clipFrames(30);
        for (const auto& f : frames) writer.write(f);
        for (int i = 0; i < 30; ++i) writer.write(cv::Mat(frames[0].size(), CV_8UC3, cv::Scalar(0, 0, 0)));
    }
    Collector vmc, ifm, osf;
    const test::CommandRun run = test::runCommand(
        FACETRACK_CLI, "send --input '" + clip + "' --protocol vmc,ifacialmocap,openseeface --fast --profile none --listen-port " +
                           std::to_string(freePort()) + " --to vmc=" + vmc.address() + ",ifacialmocap=" + ifm.address() +
                           ",openseeface=" + osf.address());
    ASSERT_EQ(run.exit_code, 0) << run.err;
    std::remove(clip.c_str());
    // A sender busy when two results came takes the newer (as with a camera): under load a few are skipped.
    long sent = 0, withFace = 0;
    ASSERT_EQ(std::sscanf(run.err.c_str() + run.err.rfind("facetrack send: ", run.err.find("frames sent")),
                          "facetrack send: %ld frames sent (a face in %ld)", &sent, &withFace),
              2)
        << run.err;
    EXPECT_GE(sent, 50);

    struct VmcFrame {
        float time = 0.f, largest = 0.f;
        int tracking = -1;
    };
    std::vector<VmcFrame> frames(1);
    for (const auto& d : vmc.finish()) {
        for (const auto& m : decodeBundle(d)) {
            if (m.address == "/VMC/Ext/Blend/Val") frames.back().largest = std::max(frames.back().largest, m.floats.at(0));
            if (m.address == "/VMC/Ext/OK") frames.back().tracking = m.ints.size() == 4 ? m.ints[3] : -1;
            if (m.address == "/VMC/Ext/T") {
                frames.back().time = m.floats.at(0);
                frames.emplace_back();
            }
        }
    }
    frames.pop_back();
    ASSERT_EQ(static_cast<long>(frames.size()), sent);
    const double faceLeaves = 30 / 30.0;
    for (const VmcFrame& f : frames) {
        EXPECT_EQ(f.tracking, f.time < faceLeaves - 1e-3 ? 1 : 0) << "at " << f.time << " s";
        if (f.time >= faceLeaves + 0.6 - 1e-3) {
            EXPECT_EQ(f.largest, 0.f) << "at " << f.time << " s";
        }
    }
    EXPECT_GT(frames.front().largest, 0.05f);  // the face showed some expression before it left
    EXPECT_EQ(frames.back().largest, 0.f);

    EXPECT_EQ(static_cast<long>(ifm.finish().size()), sent);  // the avatar easing to rest is sent too
    const auto& osfPackets = osf.finish();
    EXPECT_EQ(static_cast<long>(osfPackets.size()), withFace);  // OpenSeeFace: no packet without a face
    for (const auto& p : osfPackets) EXPECT_EQ(p.size() % kOpenSeeFaceFaceBytes, 0u);
}

}  // namespace
}  // namespace facetrack
