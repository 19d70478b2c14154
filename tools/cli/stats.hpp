#pragma once
// Summary statistics the CLI's reports share. NaN for an empty sample.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace facetrack::cli {

/// The q-quantile (0..1) by nearest rank.
inline double percentile(std::vector<double> v, double q) {
    if (v.empty()) return std::nan("");
    std::sort(v.begin(), v.end());
    return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5)];
}

inline double mean(const std::vector<double>& v) {
    double sum = 0.0;
    for (const double x : v) sum += x;
    return v.empty() ? std::nan("") : sum / static_cast<double>(v.size());
}

/// Pearson's correlation of two samples of one size (NaN when either is constant).
inline double pearson(const std::vector<double>& a, const std::vector<double>& b) {
    const double n = static_cast<double>(a.size());
    double ma = 0, mb = 0;
    for (std::size_t i = 0; i < a.size(); ++i) ma += a[i] / n, mb += b[i] / n;
    double sab = 0, saa = 0, sbb = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        sab += (a[i] - ma) * (b[i] - mb);
        saa += (a[i] - ma) * (a[i] - ma);
        sbb += (b[i] - mb) * (b[i] - mb);
    }
    return saa > 0 && sbb > 0 ? sab / std::sqrt(saa * sbb) : std::nan("");
}

/// The least-squares line y = slope x + b through two samples of one size, and the spread (RMS)
/// of y about it. Slope NaN when x is constant.
struct Line {
    double slope, spread;
};
inline Line leastSquaresLine(const std::vector<double>& x, const std::vector<double>& y) {
    const double mx = mean(x), my = mean(y);
    double xy = 0.0, xx = 0.0, yy = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        xy += (x[i] - mx) * (y[i] - my);
        xx += (x[i] - mx) * (x[i] - mx);
        yy += (y[i] - my) * (y[i] - my);
    }
    if (!(xx > 0.0)) return {std::nan(""), std::nan("")};
    const double slope = xy / xx;
    return {slope, std::sqrt(std::max(0.0, yy - slope * xy) / static_cast<double>(x.size()))};
}

}  // namespace facetrack::cli
