#include "controls.hpp"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

namespace facetrack::demo {

void Controls::press(int key) {
    switch (key) {
        case GLFW_KEY_SPACE:
            paused = !paused;
            break;
        case GLFW_KEY_M:
            mirror = !mirror;
            break;
        case GLFW_KEY_R:
            reset_identity = true;
            break;
        case GLFW_KEY_N:
            neutral = !neutral;
            neutral_changed = true;
            break;
        case GLFW_KEY_Q:
        case GLFW_KEY_ESCAPE:
            quit = true;
            break;
        default:
            break;
    }
}

}  // namespace facetrack::demo
