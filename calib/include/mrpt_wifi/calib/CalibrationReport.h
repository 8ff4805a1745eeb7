/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/calib/PhaseCalibrator.h>

#include <string>
#include <vector>

namespace mrpt_wifi::calib
{
/** Writes the report pictures of one channel into `dir` (created if needed) and returns their
 *  paths: `phases_<ch>.png` (recovered phase per antenna over subcarriers, coarse and refined)
 *  and, in drive mode, `bearing_error_<ch>.png` (CDF of the bearing error on the calibration
 *  drive before and after). `<ch>` is e.g. `ch155_80mhz`. Throws std::runtime_error if a file
 *  can't be written. */
std::vector<std::string> writeCalibrationReport(
    const ChannelCalibration& result, const std::string& dir);

/** A multi-series line chart drawn with OpenCV (labelled axes, ticks, legend), saved as PNG. */
struct ChartSeries
{
    std::vector<double> x, y;
    std::string label;
    unsigned rgb = 0x1f77b4;
    int thickness = 2;
    bool dashed = false;
};
struct Chart
{
    std::string title, xLabel, yLabel;
    std::vector<ChartSeries> series;
    double xMin = 0, xMax = 0, yMin = 0, yMax = 0;  //!< equal min and max: from the data
    bool logX = false;  //!< logarithmic x axis (values ≤ 0 are left out)
    int width = 1000, height = 600;
    void savePng(const std::string& path) const;
};

}  // namespace mrpt_wifi::calib
