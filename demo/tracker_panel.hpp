#pragma once
// The app's side panel (Dear ImGui), right of the camera and the avatar:
// fps, latency and CPU; the camera; whether the face is followed or lost; head pose and
// gaze; the calibration (neutral now, the guided capture with its prompt,
// save, reset) and mirroring; a toggle and destination per protocol to send; and a bar per
// ARKit shape, grouped (eyes; brows, jaw, cheeks, nose and tongue; mouth),
// each with its calibrated value as the bar and its raw value (before the
// filter and the calibration) as a tick.

#include "guided_calibration.hpp"

#include "facetrack/result.hpp"

#include <array>
#include <optional>
#include <string>
#include <vector>

struct GLFWwindow;

namespace facetrack::demo {

/// One protocol the app can send, as the panel shows and edits it.
struct SenderToggle {
    std::string protocol;     ///< "vmc", "ifacialmocap", "openseeface"
    bool enabled = false;     ///< edited by the panel
    std::string destination;  ///< HOST[:PORT], edited by the panel
    std::string status;       ///< what it sent, or why it cannot
};

/// What the panel shows (and, for the senders, edits).
struct PanelState {
    double fps = 0.0, latency_ms = 0.0, cpu_percent = 0.0;
    double lost_for_s = -1.0;  ///< seconds since the face was lost; < 0 while one is followed
    std::array<bool, kArkitBlendshapeCount> estimated{};
    std::string calibration_note;  ///< the profile in use, or the last capture's outcome
    std::optional<GuidedCalibration::Step> prompt;
    std::vector<SenderToggle> senders;
    bool mirror = false;               ///< edited by the panel
    std::vector<std::string> cameras;  ///< the /dev/video* there are
    int camera = -1;                   ///< the one in use (an index into cameras; -1: a clip), edited by the panel
};

/// Buttons pressed in this frame.
struct PanelClicks {
    bool neutral = false, guided = false, cancel_guided = false, save = false, reset = false;
    bool camera = false;  ///< another camera was picked (PanelState::camera)
};

class TrackerPanel {
public:
    static constexpr int kWidth = 600;
    // Colours the screenshot tests look for (RGBA).
    static constexpr std::array<unsigned char, 4> kBarOutline{96, 96, 112, 255};
    static constexpr std::array<unsigned char, 4> kFaceLost{200, 40, 40, 255};
    static constexpr std::array<unsigned char, 4> kPrompt{230, 160, 30, 255};

    /// Dear ImGui on `window`'s OpenGL 3.3 context. Set the window's own GLFW
    /// callbacks first: ImGui chains them.
    explicit TrackerPanel(GLFWwindow* window);
    ~TrackerPanel();
    TrackerPanel(const TrackerPanel&) = delete;
    TrackerPanel& operator=(const TrackerPanel&) = delete;

    /// Draws the panel at (x, 0), kWidth x height, into the bound framebuffer
    /// of a window `windowWidth` x height (after the rest of the frame).
    /// `face`: the first face of the frame, or null.
    PanelClicks draw(const FaceResult* face, PanelState& state, int x, int windowWidth, int height);

    /// A text field has the keyboard: the app's own keys must wait.
    static bool wantsKeyboard();
};

}  // namespace facetrack::demo
