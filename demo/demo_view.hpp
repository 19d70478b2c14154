#pragma once
// The app's two picture panels, left to right: the camera image with the
// tracker's overlay (landmarks, projected mesh, head axes, gaze rays) and a
// HUD with fps and per-stage timings, then the avatar.

#include "app/overlay.hpp"
#include "avatar_renderer.hpp"
#include "image_quad.hpp"

#include "facetrack/posed_mesh.hpp"

#include "facetrack/result.hpp"

#include <opencv2/core.hpp>

#include <memory>
#include <string>
#include <vector>

namespace facetrack::demo {

struct Hud {
    double fps = 0.0;                  ///< frames tracked per second, smoothed
    std::vector<StageTiming> timings;  ///< the tracker's, plus the demo's own (render)
    std::vector<std::string> notes;    ///< state lines: source, paused, calibration, problems
};

class DemoView {
public:
    /// Each panel is panelWidth x panelHeight; the window is twice as wide.
    DemoView(std::shared_ptr<const FaceModel> model, int panelWidth, int panelHeight);

    /// Draws into the current framebuffer (GlContext::beginFrame first). The
    /// avatar shows `avatar` (the first face, or one easing to rest after a
    /// loss: send::FaceLossEasing); null: the avatar at rest.
    void draw(const cv::Mat& frameBgr, const FrameResult& result, const FaceResult* avatar, const Hud& hud, bool mirror);

    /// The two panels' width.
    int width() const { return 2 * panel_width_; }
    int height() const { return panel_height_; }
    /// The avatar's panel in screenshot (top-left origin) pixels.
    cv::Rect avatarPanel() const { return {panel_width_, 0, panel_width_, panel_height_}; }

    /// Panel size for frames of `frameSize`: 480 px high, the frame's aspect.
    static cv::Size panelSizeFor(cv::Size frameSize);

private:
    MeshPoser poser_;
    std::vector<Vec3> mesh_;  // the first face's posed mesh, reused
    tools::OverlayRenderer overlay_;
    AvatarRenderer avatar_;
    ImageQuad image_;
    int panel_width_, panel_height_;
    cv::Mat annotated_;
};

}  // namespace facetrack::demo
