/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/calib/CalibrationCheck.h>
#include <mrpt_wifi/calib/CalibrationReport.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <stdexcept>

namespace mrpt_wifi::calib
{
namespace
{
cv::Scalar bgr(unsigned rgb)
{
    return cv::Scalar(rgb & 0xff, (rgb >> 8) & 0xff, (rgb >> 16) & 0xff);
}

/** Tick step: 1, 2 or 5 × 10^k giving about `target` intervals. */
double niceStep(double range, int target)
{
    const double raw = range / target;
    const double p = std::pow(10.0, std::floor(std::log10(raw)));
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * p >= raw) return m * p;
    return 10 * p;
}

std::string tickText(double v, double step)
{
    std::ostringstream o;
    const int decimals = step >= 1 ? 0 : int(std::ceil(-std::log10(step) - 1e-9));
    o.setf(std::ios::fixed);
    o.precision(decimals);
    o << (std::abs(v) < step * 1e-6 ? 0.0 : v);
    return o.str();
}

const int kFont = cv::FONT_HERSHEY_SIMPLEX;
}  // namespace

void Chart::savePng(const std::string& path) const
{
    const int left = 95, right = 30, top = 55, bottom = 75;
    cv::Mat img(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
    const auto tx = [&](double x) { return logX ? std::log10(x) : x; };

    // Data range.
    double x0 = xMin, x1 = xMax, y0 = yMin, y1 = yMax;
    if (!(x1 > x0) || !(y1 > y0))
    {
        double ax = std::numeric_limits<double>::infinity(), bx = -ax, ay = ax, by = -ax;
        for (const auto& s : series)
            for (size_t i = 0; i < s.x.size(); ++i)
            {
                if (logX && s.x[i] <= 0) continue;
                ax = std::min(ax, s.x[i]), bx = std::max(bx, s.x[i]);
                ay = std::min(ay, s.y[i]), by = std::max(by, s.y[i]);
            }
        if (!std::isfinite(ax)) ax = 0, bx = 1, ay = 0, by = 1;
        if (!(x1 > x0)) x0 = ax, x1 = bx > ax ? bx : ax + 1;
        if (!(y1 > y0))
        {
            const double pad = 0.05 * std::max(by - ay, 1e-9);
            y0 = ay - pad, y1 = by + pad;
        }
    }
    const double X0 = tx(x0), X1 = tx(x1);
    const int pw = width - left - right, ph = height - top - bottom;
    const auto px = [&](double x)
    { return left + int(std::lround((tx(x) - X0) / (X1 - X0) * pw)); };
    const auto py = [&](double y)
    { return top + ph - int(std::lround((y - y0) / (y1 - y0) * ph)); };

    // Grid, ticks, labels.
    const cv::Scalar grid(225, 225, 225), ink(0, 0, 0);
    const double ys = niceStep(y1 - y0, 8);
    for (double v = std::ceil(y0 / ys) * ys; v <= y1 + 1e-9 * ys; v += ys)
    {
        const int y = py(v);
        cv::line(img, {left, y}, {left + pw, y}, grid, 1);
        const std::string t = tickText(v, ys);
        int base = 0;
        const auto sz = cv::getTextSize(t, kFont, 0.5, 1, &base);
        cv::putText(
            img, t, {left - 8 - sz.width, y + sz.height / 2}, kFont, 0.5, ink, 1, cv::LINE_AA);
    }
    std::vector<std::pair<double, std::string>> xt;
    if (logX)
    {
        for (int e = int(std::floor(X0)); e <= int(std::ceil(X1)); ++e)
        {
            const double v = std::pow(10.0, e);
            if (v >= x0 * (1 - 1e-9) && v <= x1 * (1 + 1e-9))
                xt.emplace_back(v, tickText(v, std::min(1.0, v)));
            for (int m = 2; m <= 9; ++m)  // minor grid
                if (m * v > x0 && m * v < x1)
                    cv::line(
                        img, {px(m * v), top}, {px(m * v), top + ph}, cv::Scalar(240, 240, 240), 1);
        }
    }
    else
    {
        const double xs = niceStep(x1 - x0, 10);
        for (double v = std::ceil(x0 / xs) * xs; v <= x1 + 1e-9 * xs; v += xs)
            xt.emplace_back(v, tickText(v, xs));
    }
    for (const auto& [v, t] : xt)
    {
        const int x = px(v);
        cv::line(img, {x, top}, {x, top + ph}, grid, 1);
        int base = 0;
        const auto sz = cv::getTextSize(t, kFont, 0.5, 1, &base);
        cv::putText(
            img, t, {x - sz.width / 2, top + ph + 8 + sz.height}, kFont, 0.5, ink, 1, cv::LINE_AA);
    }
    cv::rectangle(img, {left, top}, {left + pw, top + ph}, ink, 1);

    // Axis labels (the y label rotated), title.
    {
        int base = 0;
        auto sz = cv::getTextSize(xLabel, kFont, 0.6, 1, &base);
        cv::putText(
            img, xLabel, {left + pw / 2 - sz.width / 2, height - 18}, kFont, 0.6, ink, 1,
            cv::LINE_AA);
        sz = cv::getTextSize(yLabel, kFont, 0.6, 1, &base);
        cv::Mat lab(sz.height + base + 6, sz.width + 6, CV_8UC3, cv::Scalar(255, 255, 255));
        cv::putText(lab, yLabel, {3, sz.height + 3}, kFont, 0.6, ink, 1, cv::LINE_AA);
        cv::rotate(lab, lab, cv::ROTATE_90_COUNTERCLOCKWISE);
        const int y = std::max(0, top + ph / 2 - lab.rows / 2);
        if (y + lab.rows <= img.rows) lab.copyTo(img(cv::Rect(12, y, lab.cols, lab.rows)));
        sz = cv::getTextSize(title, kFont, 0.65, 2, &base);
        cv::putText(img, title, {width / 2 - sz.width / 2, 32}, kFont, 0.65, ink, 2, cv::LINE_AA);
    }

    // Series, clipped to the plot area.
    cv::Mat plot = img(cv::Rect(left, top, pw, ph));
    for (const auto& s : series)
    {
        std::vector<cv::Point> pts;
        for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i)
        {
            if ((logX && s.x[i] <= 0) || !std::isfinite(s.y[i])) continue;
            pts.emplace_back(px(s.x[i]) - left, py(s.y[i]) - top);
        }
        double walked = 0;
        for (size_t i = 1; i < pts.size(); ++i)
        {
            const double len = cv::norm(pts[i] - pts[i - 1]);
            const bool on = !s.dashed || std::fmod(walked, 14.0) < 8.0;
            walked += len;
            if (on) cv::line(plot, pts[i - 1], pts[i], bgr(s.rgb), s.thickness, cv::LINE_AA);
        }
    }

    // Legend (top right inside the plot).
    int lw = 0, lh = 0;
    for (const auto& s : series)
    {
        if (s.label.empty()) continue;
        int base = 0;
        lw = std::max(lw, cv::getTextSize(s.label, kFont, 0.5, 1, &base).width);
        lh += 22;
    }
    if (lh > 0)
    {
        const int bx = left + pw - lw - 60, by = top + 10;
        cv::rectangle(
            img, {bx, by}, {bx + lw + 50, by + lh + 6}, cv::Scalar(255, 255, 255), cv::FILLED);
        cv::rectangle(img, {bx, by}, {bx + lw + 50, by + lh + 6}, cv::Scalar(160, 160, 160), 1);
        int y = by + 18;
        for (const auto& s : series)
        {
            if (s.label.empty()) continue;
            if (s.dashed)
            {
                cv::line(
                    img, {bx + 8, y - 5}, {bx + 18, y - 5}, bgr(s.rgb), s.thickness, cv::LINE_AA);
                cv::line(
                    img, {bx + 26, y - 5}, {bx + 36, y - 5}, bgr(s.rgb), s.thickness, cv::LINE_AA);
            }
            else
                cv::line(
                    img, {bx + 8, y - 5}, {bx + 36, y - 5}, bgr(s.rgb), s.thickness, cv::LINE_AA);
            cv::putText(img, s.label, {bx + 44, y}, kFont, 0.5, ink, 1, cv::LINE_AA);
            y += 22;
        }
    }
    if (!cv::imwrite(path, img)) throw std::runtime_error("cannot write picture '" + path + "'");
}

namespace
{
const unsigned kColours[] = {0x1f77b4, 0xd62728, 0x2ca02c, 0x9467bd, 0xff7f0e, 0x8c564b, 0xe377c2};

std::vector<double> unwrappedDeg(const std::vector<double>& rad)
{
    std::vector<double> out(rad.size());
    double prev = 0;
    for (size_t j = 0; j < rad.size(); ++j)
    {
        const double v = j == 0 ? rad[0] : prev + wrapAngle(rad[j] - prev);
        out[j] = v;
        prev = v;
    }
    // Centre the curve so its mean lies in (−180°, 180°].
    double mean = 0;
    for (double v : out) mean += v;
    mean /= double(std::max<size_t>(1, out.size()));
    const double shift = wrapAngle(mean) - mean;
    for (double& v : out) v = (v + shift) * 180 / M_PI;
    return out;
}

std::pair<std::vector<double>, std::vector<double>> cdf(std::vector<double> v)
{
    std::sort(v.begin(), v.end());
    std::vector<double> y(v.size());
    for (size_t i = 0; i < v.size(); ++i) y[i] = double(i + 1) / double(v.size());
    return {v, y};
}

std::string fixed(double v, int p)
{
    std::ostringstream o;
    o.setf(std::ios::fixed);
    o.precision(p);
    o << v;
    return o.str();
}
}  // namespace

std::vector<std::string> writeCalibrationReport(
    const ChannelCalibration& result, const std::string& dir)
{
    if (!mrpt::system::directoryExists(dir) && !mrpt::system::createDirectory(dir))
        throw std::runtime_error("cannot create report folder '" + dir + "'");
    const auto& c = result.calibration;
    std::string tag = PhaseCalibration::fileNameFor(c.chanspec);
    tag = tag.substr(0, tag.rfind('.'));
    std::vector<std::string> written;

    Chart ph;
    ph.title = "Recovered phase calibration, " + c.device + " on " + c.chanspec.asString() + " (" +
               std::to_string(c.framesUsed) + " frames, residual " +
               fixed(c.residual_rad * 180 / M_PI, 1) + " deg)";
    ph.xLabel = "subcarrier index k";
    ph.yLabel = "phase relative to antenna 0 [deg]";
    std::vector<double> k(c.subcarriers.begin(), c.subcarriers.end());
    for (size_t i = 1; i < c.antennas(); ++i)
    {
        const unsigned col = kColours[(i - 1) % 7];
        ChartSeries fine{
            k,    unwrappedDeg(c.phases_rad[i]), "antenna " + std::to_string(i) + " (LM)", col, 2,
            false};
        ph.series.push_back(fine);
        if (i < result.coarsePhases_rad.size())
        {
            ChartSeries coarse{k,
                               unwrappedDeg(result.coarsePhases_rad[i]),
                               "antenna " + std::to_string(i) + " (PCA)",
                               col,
                               1,
                               true};
            // Same 2π branch as the refined curve, so the two overlay.
            const double off = std::round((fine.y.front() - coarse.y.front()) / 360.0) * 360.0;
            for (double& v : coarse.y) v += off;
            ph.series.push_back(coarse);
        }
    }
    const std::string phPath = dir + "/phases_" + tag + ".png";
    ph.savePng(phPath);
    written.push_back(phPath);

    if (!result.bearingErrorBefore_deg.empty())
    {
        Chart be;
        be.title = "Bearing error on the calibration drive, " + c.chanspec.asString() + " (" +
                   std::to_string(result.bearingErrorAfter_deg.size()) + " frames)";
        be.xLabel = "|bearing error| [deg] (log scale)";
        be.yLabel = "fraction of frames";
        be.logX = true;
        be.xMin = 0.01;
        be.xMax = 180;
        be.yMin = 0;
        be.yMax = 1.0;
        auto [xb, yb] = cdf(result.bearingErrorBefore_deg);
        auto [xa, ya] = cdf(result.bearingErrorAfter_deg);
        be.series.push_back(
            {xb, yb,
             "uncalibrated (median " + fixed(quantile(result.bearingErrorBefore_deg, 0.5), 1) +
                 " deg)",
             0xd62728, 2, false});
        be.series.push_back(
            {xa, ya,
             "calibrated (median " + fixed(quantile(result.bearingErrorAfter_deg, 0.5), 2) +
                 " deg)",
             0x1f77b4, 2, false});
        const std::string bePath = dir + "/bearing_error_" + tag + ".png";
        be.savePng(bePath);
        written.push_back(bePath);
    }
    return written;
}

}  // namespace mrpt_wifi::calib
