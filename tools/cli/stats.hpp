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

}  // namespace facetrack::cli
