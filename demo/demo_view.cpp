#include "demo_view.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdio>

namespace facetrack::demo {

namespace {

/// The HUD as a BGRA strip: text on a half-transparent dark background.
cv::Mat hudImage(const std::vector<std::string>& lines, int maxWidth) {
    constexpr int kLine = 18, kMargin = 6;
    constexpr double kScale = 0.45;
    int width = 0;
    for (const auto& line : lines) {
        int baseline = 0;
        width = std::max(width, cv::getTextSize(line, cv::FONT_HERSHEY_SIMPLEX, kScale, 1, &baseline).width);
    }
    cv::Mat hud(kLine * static_cast<int>(lines.size()) + 2 * kMargin, std::min(maxWidth, width + 2 * kMargin), CV_8UC4,
                cv::Scalar(20, 20, 20, 170));
    for (std::size_t i = 0; i < lines.size(); ++i) {
        cv::putText(hud, lines[i], cv::Point(kMargin, kMargin + kLine * static_cast<int>(i + 1) - 5), cv::FONT_HERSHEY_SIMPLEX, kScale,
                    cv::Scalar(235, 235, 235, 255), 1, cv::LINE_AA);
    }
    return hud;
}

std::string timingLine(const std::vector<StageTiming>& timings) {
    std::string line;
    double total = 0.0;
    char buf[64];
    for (const auto& t : timings) {
        total += t.ms;
        if (t.ms < 0.05) continue;  // where the time does not go: the line must fit its panel
        std::snprintf(buf, sizeof buf, "%s %.1f  ", t.stage.c_str(), t.ms);
        line += buf;
    }
    std::snprintf(buf, sizeof buf, "| %.1f ms", total);
    return line + buf;
}

}  // namespace

cv::Size DemoView::panelSizeFor(cv::Size frameSize) {
    constexpr int kHeight = 480;
    const double aspect = frameSize.height > 0 ? static_cast<double>(frameSize.width) / frameSize.height : 4.0 / 3.0;
    return {std::clamp(static_cast<int>(std::lround(kHeight * aspect)) / 2 * 2, 270, 960), kHeight};
}

DemoView::DemoView(std::shared_ptr<const FaceModel> model, int panelWidth, int panelHeight)
    : poser_(model), overlay_(model), avatar_(model), panel_width_(panelWidth), panel_height_(panelHeight) {}

void DemoView::draw(const cv::Mat& frameBgr, const FrameResult& result, const FaceResult* avatar, const Hud& hud, bool mirror) {
    // The first face's mesh is posed once, for the overlay and (when it is the avatar's face) the avatar both.
    const FaceResult* face = result.faces.empty() ? nullptr : &result.faces.front();
    const bool posed = face && face->pose && face->expression;
    if (posed) poser_.modelFrame(*face, mesh_);
    if (!frameBgr.empty()) {
        frameBgr.copyTo(annotated_);
        overlay_.draw(annotated_, result, posed ? &mesh_ : nullptr);
        image_.draw(annotated_, 0, 0, panel_width_, panel_height_, mirror);
    }
    if (avatar && avatar->pose && avatar->expression) {
        if (avatar != face) poser_.modelFrame(*avatar, mesh_);
        avatar_.drawMesh(mesh_, avatar->pose->rotation, panel_width_, 0, panel_width_, panel_height_, mirror);
    } else {
        avatar_.draw(avatar ? AvatarState::of(*avatar) : AvatarState{}, panel_width_, 0, panel_width_, panel_height_, mirror);
    }

    char first[96];
    std::snprintf(first, sizeof first, "%.1f fps   %s", hud.fps,
                  result.faces.empty() ? "no face" : (std::to_string(result.faces.size()) + " face(s)").c_str());
    std::vector<std::string> lines = {first, timingLine(hud.timings)};
    if (!result.faces.empty() && result.faces.front().pose) {
        const auto& face = result.faces.front();
        const Vec3 e = face.pose->euler_deg;
        char pose[128];
        std::snprintf(pose, sizeof pose, "id %d  pitch %+.0f  yaw %+.0f  roll %+.0f  distance %.0f cm  %s", face.id, e.x, e.y, e.z,
                      face.pose->translation_mm.z / 10.f, face.identity_calibrated ? "identity calibrated" : "calibrating identity...");
        lines.push_back(pose);
    }
    lines.insert(lines.end(), hud.notes.begin(), hud.notes.end());
    lines.push_back("space pause   r reset identity   n neutral   m mirror   q quit");
    const cv::Mat text = hudImage(lines, width());
    // Top-left corner; GL's viewport origin is the bottom-left.
    image_.draw(text, 0, panel_height_ - text.rows, text.cols, text.rows, false);
}

}  // namespace facetrack::demo
