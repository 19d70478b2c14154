// facetrack send: track a camera or a clip and stream the results to an avatar
// app over VMC, iFacialMocap or OpenSeeFace (docs/protocols.md, docs/embedding.md).

#include "commands.hpp"
#include "stats.hpp"

#include "send/sender.hpp"

#include "facetrack/async_tracker.hpp"

#include "app/process_cpu.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>

namespace facetrack::cli {

namespace {

const char* kUsage = R"(usage: facetrack send (--camera /dev/videoN | --input CLIP|DIR) --protocol PROTOCOL[,PROTOCOL...]
                      [--to HOST[:PORT] | --to PROTOCOL=HOST[:PORT],...] [--listen-port P] [--frames N]
                      [--fast] [--size WxH] [--fps F] [--profile FILE|none] [tracker options]
Tracks on its own thread and sends every tracked frame to avatar apps over UDP, in one or
more protocols at once (--protocol vmc,openseeface):
  vmc            VMC protocol (OSC): Perfect Sync and VRM blend shapes, Head/Neck/eye bones
                 (VSeeFace, VNyan, Warudo, VMagicMirror, EVMC4U; default port 39539)
  ifacialmocap   iFacialMocap's text protocol (default port 49983); answers a receiver's
                 handshake heard on --listen-port (default 49983)
  openseeface    OpenSeeFace's 1785-byte binary packet per face (default port 11573)
--to defaults to 127.0.0.1 on each protocol's port; --to HOST sends every protocol to HOST,
--to vmc=HOST:PORT,openseeface=HOST2 each to its own. When the face is lost, VMC says so
(/VMC/Ext/OK tracking status 0) and VMC and iFacialMocap ease the avatar to rest over 0.5 s;
OpenSeeFace sends nothing. --profile applies a calibration profile ('facetrack calibrate'; by
default the user's, when there is one; none: no calibration). A clip plays at its own rate, dropping
frames the tracker is too slow for, as a camera would; --fast tracks every frame as fast as
possible. --size and --fps are what the camera is asked for (default 640x480, 30).
Sending never waits on the network: a receiver that is not there costs nothing. Ctrl+C
stops; at the end it prints frames, datagrams, capture-to-sent latency and CPU use.
docs/embedding.md says how to set up each app.)";

volatile std::sig_atomic_t g_interrupted = 0;
void onInterrupt(int) { g_interrupted = 1; }

/// --camera DEVICE [--size WxH] [--fps F], checked before anything opens.
CaptureSettings cameraSettings(const Args& args) {
    CaptureSettings settings;
    settings.device = args.get("--camera");
    if (args.has("--size")) {
        const cv::Size size = parseSize(args.get("--size"));
        settings.width = size.width;
        settings.height = size.height;
    }
    settings.fps = args.number("--fps", settings.fps);
    if (!(settings.fps > 0.0 && settings.fps <= 1000.0)) throw Error("--fps must be in (0, 1000]");
    return settings;
}

std::unique_ptr<FrameSource> openSource(const Args& args, const CaptureSettings& camera) {
    if (args.has("--input")) return openMediaSource(args.get("--input"));
    return openCameraSource(camera);
}

}  // namespace

int runSend(const std::vector<std::string>& argv) {
    const Args args(
        argv, trackingOptions({"--camera", "--input", "--protocol", "--to", "--listen-port", "--frames", "--size", "--fps", "--profile"}),
        trackingFlags({"--help", "--fast"}));
    if (args.has("--help")) {
        std::puts(kUsage);
        return 0;
    }
    if (!args.positional().empty()) throw Error("unexpected '" + args.positional()[0] + "' (see --help)");
    if (!args.has("--protocol")) throw Error("give --protocol vmc|ifacialmocap|openseeface (or several, comma-separated)");
    const std::vector<send::Destination> destinations = send::parseDestinations(args.get("--protocol"), args.get("--to"));
    const long maxFrames = static_cast<long>(args.integer("--frames", -1));
    std::optional<int> listenPort;
    if (args.has("--listen-port")) listenPort = args.integer("--listen-port", 0);
    if (args.has("--camera") == args.has("--input")) throw Error("give --camera DEVICE or --input CLIP (see --help)");
    const CaptureSettings camera = cameraSettings(args);
    const TrackerConfig config = trackerConfig(args);

    Models models = trackingModels(args);
    std::vector<std::unique_ptr<send::Sender>> senders;
    std::string sending;
    for (const auto& d : destinations) {
        senders.push_back(std::make_unique<send::Sender>(d.protocol, d.to, models.face, listenPort));
        sending += std::string(sending.empty() ? "" : ", ") + send::protocolName(d.protocol) + " to " + senders.back()->destination();
    }
    AsyncOptions options;
    options.realtime = !args.has("--fast");
    options.calibration = tools::userCalibration(args);
    auto source = openSource(args, camera);
    const std::string sourceName = source->describe();
    AsyncTracker tracking(std::move(models), config, std::move(source), options);
    std::fprintf(stderr, "facetrack send: from %s, %s (Ctrl+C stops)\n", sourceName.c_str(), sending.c_str());

    std::signal(SIGINT, onInterrupt);
    std::signal(SIGTERM, onInterrupt);
    const auto start = std::chrono::steady_clock::now();
    const double cpuStart = tools::processCpuSeconds();
    AsyncResult latest;
    std::vector<double> latencyMs;
    long withFace = 0, frames = 0;
    while (!g_interrupted && (maxFrames < 0 || frames < maxFrames)) {
        if (!tracking.waitForNewer(latest, 0.2)) {
            if (tracking.stats().finished) break;
            continue;
        }
        for (auto& sender : senders) sender->send(latest.result, latest.time_s);
        ++frames;
        latencyMs.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - latest.arrival).count());
        withFace += latest.result.faces.empty() ? 0 : 1;
    }
    tracking.stop();
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);

    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const AsyncStats t = tracking.stats();
    send::SenderStats s;
    for (const auto& sender : senders) {
        s.datagrams += sender->stats().datagrams;
        s.bytes += sender->stats().bytes;
        s.failed += sender->stats().failed;
    }
    std::fprintf(stderr,
                 "facetrack send: %ld frames sent (a face in %ld) in %.1f s, %ld datagrams, %ld bytes, %ld not sent; "
                 "read %ld, dropped %ld; capture to sent p50 %.2f ms, p99 %.2f ms; CPU %.0f %% of one core\n",
                 frames, withFace, wall, s.datagrams, s.bytes, s.failed, t.frames_read, t.frames_dropped, percentile(latencyMs, 0.5),
                 percentile(latencyMs, 0.99), wall > 0 ? 100.0 * (tools::processCpuSeconds() - cpuStart) / wall : 0.0);
    if (!t.error.empty()) throw Error(t.error);
    return 0;
}

}  // namespace facetrack::cli
