#include "tracker_panel.hpp"

#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <cstdio>
#include <string_view>

namespace facetrack::demo {

namespace {

ImU32 colour(const std::array<unsigned char, 4>& c) { return IM_COL32(c[0], c[1], c[2], c[3]); }

const ImU32 kText = IM_COL32(230, 230, 230, 255), kDimText = IM_COL32(120, 120, 120, 255);
const ImU32 kBarFill = IM_COL32(60, 180, 160, 255), kRawTick = IM_COL32(240, 240, 240, 255);
const ImU32 kGroupText = IM_COL32(150, 190, 255, 255);

/// The panel's three columns of shape groups: {title, name prefixes}.
struct Group {
    const char* title;
    std::vector<std::string_view> prefixes;
};
const std::array<std::vector<Group>, 3> kColumns = {{
    {{"eyes", {"eye"}}},
    {{"brows", {"brow"}}, {"jaw", {"jaw"}}, {"cheeks, nose, tongue", {"cheek", "nose", "tongue"}}},
    {{"mouth", {"mouth"}}},
}};

bool inGroup(std::string_view name, const Group& g) {
    return std::any_of(g.prefixes.begin(), g.prefixes.end(), [&](std::string_view p) { return name.rfind(p, 0) == 0; });
}

/// One column of groups, a row per shape: its name, then a bar outlined in
/// kBarOutline, filled to the reported value, with a tick at the raw one.
void drawBars(ImDrawList& draw, ImVec2 at, float width, const std::vector<Group>& groups, const FaceResult* face,
              const std::array<bool, kArkitBlendshapeCount>& estimated) {
    constexpr float kRow = 14.f, kBarHeight = 9.f;
    float label = 0.f;  // the column's longest name
    for (const std::string_view name : arkitNames()) {
        for (const Group& g : groups)
            if (inGroup(name, g)) label = std::max(label, ImGui::CalcTextSize(name.data(), name.data() + name.size()).x + 10.f);
    }
    const float barWidth = width - label - 10.f;
    float y = at.y;
    for (const Group& g : groups) {
        draw.AddText({at.x, y}, kGroupText, g.title);
        y += kRow;
        for (std::size_t k = 0; k < arkitNames().size(); ++k) {
            const std::string_view name = arkitNames()[k];
            if (!inGroup(name, g)) continue;
            draw.AddText({at.x + 4.f, y}, estimated[k] ? kText : kDimText, name.data(), name.data() + name.size());
            const ImVec2 bar0(at.x + label, y + 3.f), bar1(at.x + label + barWidth, y + 3.f + kBarHeight);
            if (face && face->expression) {
                const float w = std::clamp(face->expression->arkit[k], 0.f, 1.f);
                draw.AddRectFilled(bar0, {bar0.x + w * barWidth, bar1.y}, kBarFill);
            }
            if (face && face->raw.expression) {
                const float x = bar0.x + std::clamp(face->raw.expression->arkit[k], 0.f, 1.f) * barWidth;
                draw.AddLine({x, bar0.y - 1.f}, {x, bar1.y + 1.f}, kRawTick, 2.f);
            }
            draw.AddRect(bar0, bar1, colour(TrackerPanel::kBarOutline));
            y += kRow;
        }
    }
}

/// A full-width box of `fill` with `text` in `textColour`, `share` of it darker (a progress bar).
void statusBox(const char* text, ImU32 fill, ImU32 textColour, float share = 0.f) {
    ImDrawList& draw = *ImGui::GetWindowDrawList();
    const ImVec2 p = ImGui::GetCursorScreenPos();
    const float w = ImGui::GetContentRegionAvail().x, h = 20.f;
    draw.AddRectFilled(p, {p.x + w, p.y + h}, fill);
    if (share > 0.f) draw.AddRectFilled({p.x, p.y + h - 4.f}, {p.x + share * w, p.y + h}, IM_COL32(120, 70, 10, 255));
    draw.AddText({p.x + 6.f, p.y + 3.f}, textColour, text);
    ImGui::Dummy({w, h});
}

}  // namespace

TrackerPanel::TrackerPanel(GLFWwindow* window) {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // nothing written next to the program
    ImGui::StyleColorsDark();
    ImGui::GetStyle().AntiAliasedLines = false;  // crisp one-pixel outlines
    ImGui::GetStyle().WindowRounding = 0.f;
    ImGui_ImplGlfw_InitForOpenGL(window, true);
    ImGui_ImplOpenGL3_Init("#version 330 core");
}

TrackerPanel::~TrackerPanel() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
}

bool TrackerPanel::wantsKeyboard() { return ImGui::GetCurrentContext() && ImGui::GetIO().WantTextInput; }

PanelClicks TrackerPanel::draw(const FaceResult* face, PanelState& state, int x, int windowWidth, int height) {
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    // The frame is drawn offscreen at its own size, whatever the window's.
    ImGuiIO& io = ImGui::GetIO();
    io.DisplaySize = {static_cast<float>(windowWidth), static_cast<float>(height)};
    io.DisplayFramebufferScale = {1.f, 1.f};
    ImGui::NewFrame();
    ImGui::SetNextWindowPos({static_cast<float>(x), 0.f});
    ImGui::SetNextWindowSize({static_cast<float>(kWidth), static_cast<float>(height)});
    ImGui::Begin("facetrack", nullptr,
                 ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoSavedSettings |
                     ImGuiWindowFlags_NoBringToFrontOnFocus);
    PanelClicks clicks;
    char line[192];

    std::snprintf(line, sizeof line, "%.1f fps   latency %.1f ms   CPU %.0f %% of a core", state.fps, state.latency_ms, state.cpu_percent);
    ImGui::TextUnformatted(line);
    ImGui::SameLine(static_cast<float>(kWidth) - 190.f);
    ImGui::SetNextItemWidth(180.f);
    const char* inUse = state.camera >= 0       ? state.cameras[static_cast<std::size_t>(state.camera)].c_str()
                        : state.cameras.empty() ? "no camera"
                                                : "a clip; pick a camera";
    if (ImGui::BeginCombo("##camera", inUse)) {
        for (std::size_t i = 0; i < state.cameras.size(); ++i) {
            if (ImGui::Selectable(state.cameras[i].c_str(), static_cast<int>(i) == state.camera) && static_cast<int>(i) != state.camera) {
                state.camera = static_cast<int>(i);
                clicks.camera = true;
            }
        }
        ImGui::EndCombo();
    }
    if (state.lost_for_s >= 0.0) {
        std::snprintf(line, sizeof line, "FACE LOST  %.1f s: the avatar relaxes to rest", state.lost_for_s);
        statusBox(line, colour(kFaceLost), IM_COL32(255, 255, 255, 255));
    } else if (face) {
        std::snprintf(line, sizeof line, "tracking face %d   confidence %.2f   %s", face->id, face->confidence,
                      face->identity_calibrated ? "identity calibrated" : "calibrating identity...");
        statusBox(line, IM_COL32(40, 110, 60, 255), IM_COL32(255, 255, 255, 255));
    } else {
        statusBox("looking for a face...", IM_COL32(70, 70, 70, 255), kText);
    }
    if (face && face->pose) {
        const Vec3 e = face->pose->euler_deg;
        std::snprintf(line, sizeof line, "head pitch %+.0f yaw %+.0f roll %+.0f  %.0f cm", e.x, e.y, e.z,
                      face->pose->translation_mm.z / 10.f);
        if (face->gaze) {
            const GazeResult& g = *face->gaze;
            const std::string head = line;
            std::snprintf(line, sizeof line, "%s   gaze L %+.0f/%+.0f R %+.0f/%+.0f  open %.2f/%.2f", head.c_str(), g.left.yaw_deg,
                          g.left.pitch_deg, g.right.yaw_deg, g.right.pitch_deg, g.left.openness, g.right.openness);
        }
        ImGui::TextUnformatted(line);
    } else {
        ImGui::TextDisabled("head -   gaze -");
    }

    if (state.prompt) {
        clicks.cancel_guided = ImGui::Button("Cancel calibration");
    } else {
        clicks.neutral = ImGui::Button("Neutral now");
        ImGui::SameLine();
        clicks.guided = ImGui::Button("Guided calibration");
        ImGui::SameLine();
        clicks.save = ImGui::Button("Save profile");
        ImGui::SameLine();
        clicks.reset = ImGui::Button("Reset");
    }
    ImGui::SameLine(static_cast<float>(kWidth) - 80.f);
    ImGui::Checkbox("mirror", &state.mirror);
    if (state.prompt) {
        const GuidedCalibration::Step& p = *state.prompt;
        std::snprintf(line, sizeof line, "%zu/%zu  %s%s", p.index + 1, p.count, p.instruction.c_str(), p.measuring ? "" : "  (get ready)");
        statusBox(line, colour(kPrompt), IM_COL32(0, 0, 0, 255), static_cast<float>(p.progress));
    } else {
        ImGui::TextUnformatted(state.calibration_note.c_str());
    }

    for (std::size_t i = 0; i < state.senders.size(); ++i) {
        SenderToggle& s = state.senders[i];
        ImGui::PushID(static_cast<int>(i));
        if (i > 0) ImGui::SameLine();
        ImGui::Checkbox(s.protocol.c_str(), &s.enabled);
        ImGui::SameLine();
        ImGui::SetNextItemWidth(84.f);
        ImGui::InputText("##to", &s.destination);
        if (!s.status.empty() && ImGui::IsItemHovered()) ImGui::SetTooltip("%s", s.status.c_str());
        ImGui::PopID();
    }

    ImGui::Separator();
    // Columns as wide as their share of the panel; the mouth's names are the longest.
    const ImVec2 origin = ImGui::GetCursorScreenPos();
    const std::array<float, 3> share = {0.31f, 0.33f, 0.36f};
    float left = origin.x;
    for (std::size_t c = 0; c < kColumns.size(); ++c) {
        const float width = share[c] * (static_cast<float>(kWidth) - 16.f);
        drawBars(*ImGui::GetWindowDrawList(), {left, origin.y}, width, kColumns[c], face, state.estimated);
        left += width;
    }
    ImGui::End();
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    return clicks;
}

}  // namespace facetrack::demo
