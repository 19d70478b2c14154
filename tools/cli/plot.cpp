#include "plot.hpp"

#include "facetrack/error.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdio>
#include <iterator>

namespace facetrack::cli {

void writeLinePlot(const std::string& path, const LinePlot& plot) {
    const int width = 900, height = 600, left = 80, right = 20, top = 50, bottom = 70;
    cv::Mat img(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
    const int plotW = width - left - right, plotH = height - top - bottom;
    auto toPixel = [&](double x, double y) {
        x = std::clamp(x / plot.x_max, 0.0, 1.0);
        y = std::clamp(y / plot.y_max, 0.0, 1.0);
        return cv::Point(left + static_cast<int>(x * plotW), top + plotH - static_cast<int>(y * plotH));
    };
    const auto font = cv::FONT_HERSHEY_SIMPLEX;
    const cv::Scalar black(0, 0, 0), grid(225, 225, 225);
    char label[32];
    for (int i = 0; i <= plot.x_ticks; ++i) {
        const double x = plot.x_max * i / plot.x_ticks;
        cv::line(img, toPixel(x, 0), toPixel(x, plot.y_max), grid);
        std::snprintf(label, sizeof label, plot.x_tick_format.c_str(), x * plot.x_tick_scale);
        cv::putText(img, label, toPixel(x, 0) + cv::Point(-12, 22), font, 0.45, black, 1, cv::LINE_AA);
    }
    for (int i = 0; i <= plot.y_ticks; ++i) {
        const double y = plot.y_max * i / plot.y_ticks;
        cv::line(img, toPixel(0, y), toPixel(plot.x_max, y), grid);
        std::snprintf(label, sizeof label, plot.y_tick_format.c_str(), y);
        cv::putText(img, label, toPixel(0, y) + cv::Point(-45, 5), font, 0.45, black, 1, cv::LINE_AA);
    }
    cv::rectangle(img, toPixel(0, plot.y_max), toPixel(plot.x_max, 0), black);
    cv::putText(img, plot.x_label, cv::Point(left + 150, height - 20), font, 0.55, black, 1, cv::LINE_AA);
    cv::putText(img, plot.y_label, cv::Point(10, top - 15), font, 0.5, black, 1, cv::LINE_AA);
    cv::putText(img, plot.title, cv::Point(left + 200, top - 15), font, 0.6, black, 1, cv::LINE_AA);

    const cv::Scalar colours[] = {{200, 80, 20}, {30, 30, 220}, {40, 150, 40}, {150, 40, 150}, {0, 140, 220}, {90, 90, 90}};
    for (std::size_t c = 0; c < plot.series.size(); ++c) {
        std::vector<cv::Point> line;
        for (const auto& [x, y] : plot.series[c].points) line.push_back(toPixel(x, y));
        const cv::Scalar colour = colours[c % std::size(colours)];
        if (!line.empty()) cv::polylines(img, line, false, colour, line.size() > 400 ? 1 : 2, cv::LINE_AA);
        const cv::Point legend(left + 20, top + 25 + 25 * static_cast<int>(c));
        cv::line(img, legend, legend + cv::Point(30, 0), colour, 3, cv::LINE_AA);
        cv::putText(img, plot.series[c].label, legend + cv::Point(40, 5), font, 0.5, black, 1, cv::LINE_AA);
    }
    if (!cv::imwrite(path, img)) throw Error("cannot write plot '" + path + "'");
}

}  // namespace facetrack::cli
