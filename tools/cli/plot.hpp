#pragma once
// Line plots as PNG files (OpenCV drawing: no plotting dependency).

#include <string>
#include <utility>
#include <vector>

namespace facetrack::cli {

struct PlotSeries {
    std::string label;
    std::vector<std::pair<double, double>> points;  ///< (x, y), drawn in order
};

struct LinePlot {
    std::string title, x_label, y_label;
    double x_max = 1.0, y_max = 1.0;  ///< axes run from 0
    int x_ticks = 10, y_ticks = 10;
    std::string x_tick_format = "%.1f", y_tick_format = "%.1f";  ///< printf formats of a tick's value
    double x_tick_scale = 1.0;                                   ///< a tick shows value * scale (e.g. 100 for per cent)
    std::vector<PlotSeries> series;
};

/// Throws Error when the file cannot be written.
void writeLinePlot(const std::string& path, const LinePlot& plot);

}  // namespace facetrack::cli
