/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/obs/bearing/BearingImages.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <opencv2/imgproc.hpp>
#include <sstream>

namespace mrpt_wifi::bearing
{
namespace
{
const cv::Scalar kInk(40, 40, 40), kGrid(225, 225, 225), kWhite(255, 255, 255);
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;

/** Distinct line colours (BGR), one per antenna. */
cv::Scalar lineColour(size_t i)
{
    static const cv::Scalar palette[] = {{180, 119, 31},  {14, 127, 255},  {44, 160, 44},
                                         {40, 39, 214},   {189, 103, 148}, {75, 86, 140},
                                         {194, 119, 227}, {127, 127, 127}};
    return palette[i % 8];
}

std::string fmt(double v, int decimals)
{
    std::ostringstream o;
    o << std::fixed << std::setprecision(decimals) << v;
    return o.str();
}

/** "Nice" tick step for a range and a rough number of ticks. */
double niceStep(double range, int ticks)
{
    const double raw = range / std::max(ticks, 1);
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
        if (raw <= m * mag) return m * mag;
    return 10 * mag;
}

void centredText(cv::Mat& img, const std::string& s, cv::Point c, double scale, int thick = 1)
{
    int base = 0;
    const cv::Size sz = cv::getTextSize(s, kFont, scale, thick, &base);
    cv::putText(
        img, s, {c.x - sz.width / 2, c.y + sz.height / 2}, kFont, scale, kInk, thick, cv::LINE_AA);
}

/** A plot area inside an image with data ranges and labelled axes. */
struct Axes
{
    cv::Rect area;
    double x0, x1, y0, y1;
    int px(double x) const { return area.x + int(std::lround((x - x0) / (x1 - x0) * area.width)); }
    int py(double y) const
    {
        return area.y + area.height - int(std::lround((y - y0) / (y1 - y0) * area.height));
    }

    void draw(
        cv::Mat& img, const std::string& xLabel, const std::string& yLabel, int xDecimals,
        int yDecimals, bool grid = true) const
    {
        const double sx = niceStep(x1 - x0, 8), sy = niceStep(y1 - y0, 5);
        for (double x = std::ceil(x0 / sx) * sx; x <= x1 + 1e-9; x += sx)
        {
            if (grid) cv::line(img, {px(x), area.y}, {px(x), area.y + area.height}, kGrid, 1);
            cv::line(
                img, {px(x), area.y + area.height}, {px(x), area.y + area.height + 5}, kInk, 1);
            centredText(img, fmt(x, xDecimals), {px(x), area.y + area.height + 16}, 0.42);
        }
        int widest = 0;
        for (double y = std::ceil(y0 / sy) * sy; y <= y1 + 1e-9; y += sy)
        {
            if (grid) cv::line(img, {area.x, py(y)}, {area.x + area.width, py(y)}, kGrid, 1);
            cv::line(img, {area.x - 5, py(y)}, {area.x, py(y)}, kInk, 1);
            const std::string s = fmt(std::abs(y) < 1e-9 ? 0.0 : y, yDecimals);
            int base = 0;
            const auto sz = cv::getTextSize(s, kFont, 0.42, 1, &base);
            widest = std::max(widest, sz.width);
            cv::putText(
                img, s, {area.x - 8 - sz.width, py(y) + sz.height / 2}, kFont, 0.42, kInk, 1,
                cv::LINE_AA);
        }
        cv::rectangle(img, area, kInk, 1);
        centredText(img, xLabel, {area.x + area.width / 2, area.y + area.height + 36}, 0.5);
        // Vertical y label: draw on a strip and rotate.
        int base = 0;
        const auto sz = cv::getTextSize(yLabel, kFont, 0.5, 1, &base);
        cv::Mat strip(sz.height + base + 4, sz.width + 4, CV_8UC3, kWhite);
        cv::putText(strip, yLabel, {2, sz.height + 1}, kFont, 0.5, kInk, 1, cv::LINE_AA);
        cv::Mat rotated;
        cv::rotate(strip, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
        const int x = std::max(2, area.x - 14 - widest - rotated.cols);
        const int y =
            std::clamp(area.y + area.height / 2 - rotated.rows / 2, 0, img.rows - rotated.rows);
        if (x + rotated.cols <= img.cols)
            rotated.copyTo(img(cv::Rect(x, y, rotated.cols, rotated.rows)));
    }
};

void polyline(
    cv::Mat& img, const Axes& ax, const std::vector<double>& x, const std::vector<double>& y,
    const cv::Scalar& colour)
{
    std::vector<cv::Point> pts;
    for (size_t i = 0; i < x.size(); ++i)
        pts.emplace_back(ax.px(x[i]), ax.py(std::clamp(y[i], ax.y0, ax.y1)));
    cv::polylines(img, pts, false, colour, 2, cv::LINE_AA);
}

mrpt::img::CImage toCImage(const cv::Mat& bgr)
{
    // CImage keeps OpenCV's BGR order internally, as cv::imwrite expects.
    return mrpt::img::CImage(bgr, mrpt::img::DEEP_COPY);
}
}  // namespace

mrpt::img::CImage renderMagnitudePhase(
    const std::vector<int>& subcarriers, const std::vector<std::vector<std::complex<float>>>& csi,
    const std::string& title)
{
    const int W = 900, H = 640;
    cv::Mat img(H, W, CV_8UC3, kWhite);
    centredText(img, title, {W / 2, 18}, 0.55);
    if (subcarriers.empty() || csi.empty()) return toCImage(img);

    std::vector<double> x(subcarriers.begin(), subcarriers.end());
    std::vector<std::vector<double>> mag(csi.size()), phase(csi.size());
    double mMin = 1e9, mMax = -1e9, pMin = 1e9, pMax = -1e9;
    for (size_t a = 0; a < csi.size(); ++a)
    {
        double prev = 0, offset = 0;
        for (size_t j = 0; j < csi[a].size(); ++j)
        {
            const double m = 20 * std::log10(std::max(double(std::abs(csi[a][j])), 1e-12));
            mag[a].push_back(m);
            const double p = std::arg(csi[a][j]);
            if (j > 0) offset += std::remainder(p - prev, 2 * M_PI) - (p - prev);
            phase[a].push_back(p + offset);
            prev = p;
        }
        for (double m : mag[a])
            if (std::isfinite(m) && m > -200) mMin = std::min(mMin, m), mMax = std::max(mMax, m);
        for (double p : phase[a]) pMin = std::min(pMin, p), pMax = std::max(pMax, p);
    }
    mMax += 2;
    mMin = std::max(mMin - 2, mMax - 60);
    if (pMax - pMin < 1) pMin -= 0.5, pMax += 0.5;

    const Axes top{cv::Rect(100, 40, W - 210, 230), x.front(), x.back(), mMin, mMax};
    const Axes bottom{cv::Rect(100, 340, W - 210, 230), x.front(), x.back(), pMin, pMax};
    top.draw(img, "subcarrier k", "magnitude [dB]", 0, 0);
    bottom.draw(img, "subcarrier k", "unwrapped phase [rad]", 0, pMax - pMin > 10 ? 0 : 1);
    for (size_t a = 0; a < csi.size(); ++a)
    {
        polyline(img, top, x, mag[a], lineColour(a));
        polyline(img, bottom, x, phase[a], lineColour(a));
        const int ly = 60 + int(a) * 22;
        cv::line(img, {W - 100, ly}, {W - 70, ly}, lineColour(a), 3);
        cv::putText(
            img, "rx " + std::to_string(a), {W - 64, ly + 5}, kFont, 0.45, kInk, 1, cv::LINE_AA);
    }
    return toCImage(img);
}

mrpt::img::CImage renderMagnitudePhase(const CleanCsi& f, unsigned stream)
{
    std::vector<std::vector<std::complex<float>>> csi(f.nRx);
    stream = std::min(stream, f.nTx ? f.nTx - 1 : 0);
    for (unsigned i = 0; i < f.nRx; ++i)
        for (Eigen::Index j = 0; j < f.H.cols(); ++j)
            csi[i].push_back(f.H(Eigen::Index(stream * f.nRx + i), j));
    std::ostringstream t;
    t << "CSI " << f.transmitter.asString() << "  " << f.chanspec.asString() << "  stream "
      << int(f.streamIndex.empty() ? 0 : f.streamIndex[stream]) << "  (preprocessed"
      << (f.calibrated ? ", calibrated" : ", uncalibrated") << ")";
    return renderMagnitudePhase(f.layout->subcarriers, csi, t.str());
}

mrpt::img::CImage renderMagnitudePhase(const CObservationWiFiCSI& f, unsigned stream)
{
    const auto& ks = f.dataSubcarriers();
    std::vector<std::vector<std::complex<float>>> csi;
    for (unsigned i = 0; i < f.nRx; ++i) csi.push_back(f.dataSubcarrierCsi(stream, i));
    std::ostringstream t;
    t << "CSI " << f.transmitter.asString() << "  " << f.chanspec.asString() << "  stream "
      << stream << "  seq " << f.sequenceNumber << "  (raw)";
    return renderMagnitudePhase(ks, csi, t.str());
}

mrpt::img::CImage renderBearingProfile(
    const BearingProfile& p, const BearingResult& r, const std::string& title)
{
    const int W = 900, H = 620;
    cv::Mat img(H, W, CV_8UC3, kWhite);
    const double toDeg = 180.0 / M_PI;
    std::ostringstream sub;
    sub << std::fixed << std::setprecision(1) << "AoA " << r.aoa_rad * toDeg << " deg (sigma "
        << r.aoaStd_rad * toDeg << ")";
    if (r.aoaAmbiguous) sub << ", mirror " << r.aoaMirror_rad * toDeg << " deg";
    if (r.hasDelay) sub << ", delay " << r.delay_s * 1e9 << " ns";
    if (r.hasAod) sub << ", AoD " << r.aod_rad * toDeg << " deg";
    sub << std::setprecision(2) << ", quality " << r.quality;
    centredText(img, title, {W / 2, 16}, 0.55);
    centredText(img, sub.str(), {W / 2, 40}, 0.48);
    if (p.angles_rad.empty() || p.values.size() == 0) return toCImage(img);

    const double a0 = p.angles_rad.front() * toDeg;
    const double step = p.angles_rad.size() > 1 ? (p.angles_rad[1] - p.angles_rad[0]) * toDeg : 1;
    const double a1 = a0 + step * double(p.angles_rad.size());
    const float vmax = std::max(p.values.maxCoeff(), 1e-30f);
    const double dynamic_dB = 30;
    const auto toDb = [&](float v)
    { return std::max(10 * std::log10(std::max(v, 1e-30f) / vmax), float(-dynamic_dB)); };

    if (p.delays_s.size() <= 1)
    {
        const Axes ax{cv::Rect(100, 70, W - 160, H - 150), a0, a1, -dynamic_dB, 1};
        ax.draw(img, "bearing [deg]", p.label + " [dB]", 0, 0);
        std::vector<double> x, y;
        for (size_t i = 0; i < p.angles_rad.size(); ++i)
        {
            x.push_back(p.angles_rad[i] * toDeg);
            y.push_back(toDb(p.values(Eigen::Index(i), 0)));
        }
        polyline(img, ax, x, y, lineColour(0));
        if (p.hasPeak)
        {
            const int px = ax.px(p.peakAngle_rad * toDeg);
            cv::line(
                img, {px, ax.area.y}, {px, ax.area.y + ax.area.height}, cv::Scalar(40, 39, 214), 2);
            cv::putText(
                img, "chosen", {px + 4, ax.area.y + 16}, kFont, 0.45, cv::Scalar(40, 39, 214), 1,
                cv::LINE_AA);
        }
        return toCImage(img);
    }

    const double d0 = p.delays_s.front() * 1e9, d1 = p.delays_s.back() * 1e9;
    const Axes ax{cv::Rect(100, 60, W - 230, H - 140), a0, a1, d0, d1};
    // Heat map: rows = delay (up = later), columns = bearing.
    const int nA = int(p.values.rows()), nD = int(p.values.cols());
    cv::Mat gray(nD, nA, CV_8UC1);
    for (int a = 0; a < nA; ++a)
        for (int d = 0; d < nD; ++d)
            gray.at<uint8_t>(nD - 1 - d, a) =
                uint8_t(std::lround(255.0 * (toDb(p.values(a, d)) + dynamic_dB) / dynamic_dB));
    cv::Mat colour, scaled;
    cv::applyColorMap(gray, colour, cv::COLORMAP_VIRIDIS);
    cv::resize(colour, scaled, ax.area.size(), 0, 0, cv::INTER_LINEAR);
    scaled.copyTo(img(ax.area));
    ax.draw(img, "bearing [deg]", "relative delay [ns]", 0, 0, false);
    if (p.hasPeak)
    {
        const cv::Point c(ax.px(p.peakAngle_rad * toDeg), ax.py(p.peakDelay_s * 1e9));
        cv::circle(img, c, 9, kWhite, 2, cv::LINE_AA);
        cv::line(img, {c.x - 14, c.y}, {c.x + 14, c.y}, kWhite, 1, cv::LINE_AA);
        cv::line(img, {c.x, c.y - 14}, {c.x, c.y + 14}, kWhite, 1, cv::LINE_AA);
        cv::putText(img, "chosen", {c.x + 12, c.y - 10}, kFont, 0.45, kWhite, 1, cv::LINE_AA);
    }
    // Colour bar.
    const cv::Rect bar(W - 115, ax.area.y, 18, ax.area.height);
    cv::Mat ramp(bar.height, 1, CV_8UC1);
    for (int y = 0; y < bar.height; ++y)
        ramp.at<uint8_t>(y, 0) = uint8_t(255 - 255 * y / std::max(bar.height - 1, 1));
    cv::Mat rampColour, rampScaled;
    cv::applyColorMap(ramp, rampColour, cv::COLORMAP_VIRIDIS);
    cv::resize(rampColour, rampScaled, bar.size(), 0, 0, cv::INTER_NEAREST);
    rampScaled.copyTo(img(bar));
    cv::rectangle(img, bar, kInk, 1);
    for (int db = 0; db >= -int(dynamic_dB); db -= 10)
    {
        const int y = bar.y + int(std::lround(-db / dynamic_dB * bar.height));
        cv::line(img, {bar.x + bar.width, y}, {bar.x + bar.width + 4, y}, kInk, 1);
        cv::putText(
            img, std::to_string(db), {bar.x + bar.width + 7, y + 5}, kFont, 0.42, kInk, 1,
            cv::LINE_AA);
    }
    centredText(img, "dB", {bar.x + 9, bar.y - 12}, 0.45);
    centredText(img, p.label + " (dB re. peak)", {ax.area.x + ax.area.width / 2, H - 22}, 0.45);
    return toCImage(img);
}

mrpt::obs::CObservationImage::Ptr asImageObservation(
    const mrpt::img::CImage& image, mrpt::Clock::time_point timestamp, const std::string& label)
{
    auto obs = mrpt::obs::CObservationImage::Create();
    obs->timestamp = timestamp;
    obs->sensorLabel = label;
    obs->image = image;
    obs->cameraParams.ncols = uint32_t(image.getWidth());
    obs->cameraParams.nrows = uint32_t(image.getHeight());
    return obs;
}

}  // namespace mrpt_wifi::bearing
