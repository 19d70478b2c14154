#include "ced_plot.hpp"
#include "plot.hpp"

#include "facetrack/error.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdio>
#include <numeric>

namespace facetrack::cli {

namespace {
double cedAt(const std::vector<double>& sorted, double e) {
    return double(std::upper_bound(sorted.begin(), sorted.end(), e) - sorted.begin()) / double(sorted.size());
}
}  // namespace

ErrorSummary summarize(std::vector<double> nmes, double maxError) {
    ErrorSummary s;
    if (nmes.empty()) return s;
    std::sort(nmes.begin(), nmes.end());
    s.mean = std::accumulate(nmes.begin(), nmes.end(), 0.0) / double(nmes.size());
    const std::size_t n = nmes.size();
    s.median = n % 2 ? nmes[n / 2] : 0.5 * (nmes[n / 2 - 1] + nmes[n / 2]);
    s.failure_rate = 1.0 - cedAt(nmes, maxError);
    constexpr int kSteps = 2000;  // trapezoidal rule on a fine grid
    for (int i = 0; i < kSteps; ++i) {
        const double e0 = maxError * i / kSteps, e1 = maxError * (i + 1) / kSteps;
        s.auc += 0.5 * (cedAt(nmes, e0) + cedAt(nmes, e1)) * (e1 - e0);
    }
    s.auc /= maxError;
    return s;
}

void writeCedPlot(const std::string& path, const std::vector<CedCurve>& curves, double maxError, const std::string& title) {
    LinePlot plot;
    plot.title = title;
    plot.x_label = "NME (normalised by outer-eye-corner distance)";
    plot.y_label = "fraction of faces";
    plot.x_max = maxError;
    plot.x_ticks = 8;  // every 1 % of NME at the usual 8 %
    plot.x_tick_format = "%.0f%%";
    plot.x_tick_scale = 100.0;
    constexpr int kSteps = 400;
    for (const auto& curve : curves) {
        std::vector<double> sorted = curve.nmes;
        std::sort(sorted.begin(), sorted.end());
        PlotSeries series{curve.label, {}};
        for (int i = 0; i <= kSteps && !sorted.empty(); ++i) {
            const double e = maxError * i / kSteps;
            series.points.emplace_back(e, cedAt(sorted, e));
        }
        plot.series.push_back(std::move(series));
    }
    writeLinePlot(path, plot);
}

}  // namespace facetrack::cli
