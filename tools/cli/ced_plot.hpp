#pragma once
// Cumulative error distribution (CED) curves and their summary numbers, as
// in 300-W: the share of faces whose NME is at most e, for e in [0, max].

#include <string>
#include <vector>

namespace facetrack::cli {

struct ErrorSummary {
    double mean = 0, median = 0;
    double failure_rate = 0;  ///< share with NME > max_error
    double auc = 0;           ///< area under the CED on [0, max_error], over max_error
};

ErrorSummary summarize(std::vector<double> nmes, double maxError);

struct CedCurve {
    std::string label;
    std::vector<double> nmes;
};

/// Writes a PNG plot with one line per curve. Throws Error when it cannot be written.
void writeCedPlot(const std::string& path, const std::vector<CedCurve>& curves, double maxError, const std::string& title);

}  // namespace facetrack::cli
