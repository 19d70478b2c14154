#include "ced_plot.hpp"

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

void writeCedPlot(const std::string& path, const std::vector<CedCurve>& curves, double maxError,
                  const std::string& title) {
    const int width = 800, height = 600, left = 80, right = 20, top = 50, bottom = 70;
    cv::Mat img(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
    const int plotW = width - left - right, plotH = height - top - bottom;
    auto toPixel = [&](double e, double frac) {
        return cv::Point(left + static_cast<int>(e / maxError * plotW), top + plotH - static_cast<int>(frac * plotH));
    };
    const auto font = cv::FONT_HERSHEY_SIMPLEX;
    for (int i = 0; i <= 8; ++i) {  // vertical grid every 1% of NME
        const double e = maxError * i / 8;
        cv::line(img, toPixel(e, 0), toPixel(e, 1), cv::Scalar(225, 225, 225));
        char label[16];
        std::snprintf(label, sizeof label, "%.0f%%", e * 100);
        cv::putText(img, label, toPixel(e, 0) + cv::Point(-12, 22), font, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    }
    for (int i = 0; i <= 10; ++i) {
        const double f = i / 10.0;
        cv::line(img, toPixel(0, f), toPixel(maxError, f), cv::Scalar(225, 225, 225));
        char label[16];
        std::snprintf(label, sizeof label, "%.1f", f);
        cv::putText(img, label, toPixel(0, f) + cv::Point(-40, 5), font, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    }
    cv::rectangle(img, toPixel(0, 1), toPixel(maxError, 0), cv::Scalar(0, 0, 0));
    cv::putText(img, "NME (normalised by outer-eye-corner distance)", cv::Point(left + 150, height - 20), font, 0.55,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    cv::putText(img, "fraction of faces", cv::Point(10, top - 15), font, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    cv::putText(img, title, cv::Point(left + 150, top - 15), font, 0.6, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);

    const cv::Scalar colours[] = {{200, 80, 20}, {30, 30, 220}, {40, 150, 40}, {150, 40, 150}, {0, 140, 220}};
    for (std::size_t c = 0; c < curves.size(); ++c) {
        std::vector<double> sorted = curves[c].nmes;
        std::sort(sorted.begin(), sorted.end());
        if (sorted.empty()) continue;
        std::vector<cv::Point> line;
        for (int i = 0; i <= plotW; ++i) {
            const double e = maxError * i / plotW;
            line.push_back(toPixel(e, cedAt(sorted, e)));
        }
        const cv::Scalar colour = colours[c % std::size(colours)];
        cv::polylines(img, line, false, colour, 2, cv::LINE_AA);
        const cv::Point legend(left + 20, top + 25 + 25 * static_cast<int>(c));
        cv::line(img, legend, legend + cv::Point(30, 0), colour, 3, cv::LINE_AA);
        cv::putText(img, curves[c].label, legend + cv::Point(40, 5), font, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    }
    if (!cv::imwrite(path, img)) throw Error("cannot write plot '" + path + "'");
}

}  // namespace facetrack::cli
