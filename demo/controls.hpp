#pragma once
// The demo's keys: space pauses, r resets identity calibration, m mirrors,
// q or Esc quits. Kept apart from GLFW's callback so that tests can press them.

namespace facetrack::demo {

struct Controls {
    bool paused = false;
    bool mirror = false;
    bool reset_identity = false;   ///< set by 'r'; the frame loop acts on it and clears it
    bool neutral = false;          ///< set by 'n': take the current expression as neutral (pressed again: off)
    bool neutral_changed = false;  ///< 'n' was pressed; the frame loop acts on it and clears it
    bool quit = false;

    /// A GLFW key code (GLFW_KEY_*) was pressed.
    void press(int key);
};

}  // namespace facetrack::demo
