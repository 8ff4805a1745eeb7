/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <string>
#include <vector>

/** Charts for the localization apps, drawn by gnuplot (Debian's gnuplot-nox, pngcairo). */
namespace mrpt_wifi::localization::plot
{
struct Series
{
    std::string title;
    std::vector<double> x, y;
    std::string style = "lines lw 2";  //!< gnuplot "with ..." clause
};

struct Figure
{
    std::string title, xlabel, ylabel;
    bool equalAxes = false;  //!< maps: 1 m is 1 m on both axes
    std::vector<Series> series;
    std::vector<std::string> extra;  //!< raw gnuplot commands (labels, objects, ranges)
    int width = 1000, height = 750;
};

/** Writes the figure as PNG. Returns false with a reason if gnuplot is missing or fails. */
bool savePng(const Figure& fig, const std::string& pngPath, std::string* error = nullptr);

/** Empirical CDF of `values` as a step series (x sorted, y in [0, 1]). */
Series cdf(std::vector<double> values, const std::string& title);

/** Points of an ellipse (1-σ scaled by `k`) of a 2×2 covariance, for a series. */
Series ellipse(
    double cx, double cy, double sxx, double sxy, double syy, double k, const std::string& title,
    const std::string& style);

}  // namespace mrpt_wifi::localization::plot
