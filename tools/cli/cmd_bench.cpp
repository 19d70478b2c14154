#include "app/media.hpp"
#include "commands.hpp"
#include "plot.hpp"
#include "stats.hpp"

#include "app/image_view.hpp"
#include "facetrack/facetrack.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>

namespace facetrack::cli {

namespace {

const char* kUsage = R"(usage: facetrack bench CLIP [--frames N] [--size WxH] [--plot bench.png] [tracker options]
Decodes the clip up front, then times the tracker frame by frame: prints frames, fps, the
share of frames with a face, and mean / p50 / p99 ms per stage and in total. Writes a PNG
plot of per-frame time by stage (default: bench.png). --size 640x480 letterboxes every frame
into that size first. Run it on one core for steady numbers: taskset -c 0 facetrack bench CLIP.
Tracker options as for 'facetrack track'.)";

}  // namespace

int runBench(const std::vector<std::string>& argv) {
    const Args args(argv, trackingOptions({"--frames", "--size", "--plot"}), trackingFlags({"--help"}));
    if (args.has("--help")) {
        std::puts(kUsage);
        return 0;
    }
    if (args.positional().size() != 1) throw Error("give one clip (see --help)");
    const std::string clip = args.positional()[0];
    const int maxFrames = args.integer("--frames", -1);
    const auto size = parseSize(args.get("--size"));
    Tracker tracker(trackingModels(args), trackerConfig(args));
    const auto frames = readAllFrames(clip, maxFrames, size);

    std::vector<std::string> stageOrder;
    std::map<std::string, std::vector<double>> perStage;  // ms per frame, 0 when the stage did not run
    std::vector<double> total;
    std::vector<bool> calibratedNow;  // a face's identity calibration ran in this frame (inside "fit")
    int withFace = 0;
    FrameResult result;
    bool wasCalibrated = false;
    for (std::size_t i = 0; i < frames.size(); ++i) {
        const auto start = std::chrono::steady_clock::now();
        tracker.process(tools::viewOf(frames[i].bgr), frames[i].time_s, result);
        total.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
        withFace += result.faces.empty() ? 0 : 1;
        const bool calibrated = !result.faces.empty() && result.faces[0].identity_calibrated;
        calibratedNow.push_back(calibrated && !wasCalibrated);
        wasCalibrated = calibrated;
        for (const auto& t : result.timings) {
            if (!perStage.count(t.stage)) {
                stageOrder.push_back(t.stage);
                perStage[t.stage].assign(i, 0.0);
            }
        }
        for (auto& [stage, times] : perStage) {
            double ms = 0;
            for (const auto& t : result.timings) ms += t.stage == stage ? t.ms : 0.0;
            times.push_back(ms);
        }
    }

    const double meanMs = mean(total);
    std::printf("%s: %zu frames of %dx%d, %.1f fps (mean %.3f ms per frame), a face in %.1f %% of frames\n", clip.c_str(), frames.size(),
                frames[0].bgr.cols, frames[0].bgr.rows, meanMs > 0 ? 1000.0 / meanMs : 0.0, meanMs,
                100.0 * withFace / static_cast<double>(frames.size()));
    std::printf("%-10s %6s %9s %9s %9s\n", "stage", "runs", "mean ms", "p50 ms", "p99 ms");
    for (const auto& stage : stageOrder) {
        const auto& times = perStage[stage];
        const auto runs = std::count_if(times.begin(), times.end(), [](double t) { return t > 0.0; });
        std::printf("%-10s %6ld %9.3f %9.3f %9.3f\n", stage.c_str(), static_cast<long>(runs), mean(times), percentile(times, 0.5),
                    percentile(times, 0.99));
    }
    std::printf("%-10s %6zu %9.3f %9.3f %9.3f\n", "total", total.size(), meanMs, percentile(total, 0.5), percentile(total, 0.99));
    // Tracking mode: frames that neither searched for a face nor calibrated identity (one-off costs).
    std::vector<double> tracking;
    for (std::size_t i = 0; i < total.size(); ++i) {
        const bool oneOff = (perStage.count("detect") && perStage["detect"][i] > 0) || calibratedNow[i];
        if (!oneOff) tracking.push_back(total[i]);
    }
    std::printf("%-10s %6zu %9.3f %9.3f %9.3f   (frames without detect or calibrate)\n", "tracking", tracking.size(), mean(tracking),
                percentile(tracking, 0.5), percentile(tracking, 0.99));

    LinePlot plot;
    plot.title = "facetrack bench: time per frame by stage";
    plot.x_label = "frame";
    plot.y_label = "ms";
    plot.x_max = static_cast<double>(frames.size());
    plot.x_tick_format = "%.0f";
    plot.y_max = std::max(1.0, 1.2 * percentile(total, 0.99));
    plot.y_tick_format = "%.1f";
    auto seriesOf = [](const std::string& label, const std::vector<double>& times) {
        PlotSeries s{label, {}};
        for (std::size_t i = 0; i < times.size(); ++i) s.points.emplace_back(static_cast<double>(i), times[i]);
        return s;
    };
    plot.series.push_back(seriesOf("total", total));
    for (const auto& stage : stageOrder) plot.series.push_back(seriesOf(stage, perStage[stage]));
    const std::string plotPath = args.get("--plot", "bench.png");
    writeLinePlot(plotPath, plot);
    std::printf("plot: %s\n", plotPath.c_str());
    return 0;
}

}  // namespace facetrack::cli
