/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/localization/Plot.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace mrpt_wifi::localization::plot
{
namespace
{
std::string quote(const std::string& s)
{
    std::string o = "\"";
    for (char c : s)
    {
        if (c == '"' || c == '\\') o += '\\';
        if (c == '_') o += "\\\\";  // no subscripts in titles
        o += c;
    }
    return o + "\"";
}
}  // namespace

bool savePng(const Figure& fig, const std::string& png, std::string* error)
{
    std::ostringstream g;
    g.precision(9);
    g << "set terminal pngcairo size " << fig.width << "," << fig.height
      << " enhanced font 'Sans,11'\n";
    g << "set output '" << png << "'\n";  // a path: no escaping of '_'
    if (png.find('\'') != std::string::npos)
    {
        if (error) *error = "PNG path must not contain a quote: " + png;
        return false;
    }
    g << "set title " << quote(fig.title) << "\nset xlabel " << quote(fig.xlabel) << "\nset ylabel "
      << quote(fig.ylabel) << "\nset grid\nset key outside right top\n";
    if (fig.equalAxes) g << "set size ratio -1\n";
    for (const auto& e : fig.extra) g << e << "\n";
    // Inline data blocks keep the figure self-contained (no temporary files).
    for (size_t i = 0; i < fig.series.size(); ++i)
    {
        g << "$d" << i << " << EOD\n";
        const auto& s = fig.series[i];
        for (size_t k = 0; k < s.x.size() && k < s.y.size(); ++k)
        {
            if (std::isnan(s.x[k]) || std::isnan(s.y[k]))
                g << "\n";  // a gap in a line
            else
                g << s.x[k] << " " << s.y[k] << "\n";
        }
        g << "EOD\n";
    }
    g << "plot ";
    bool any = false;
    for (size_t i = 0; i < fig.series.size(); ++i)
    {
        if (fig.series[i].x.empty()) continue;
        g << (any ? ", " : "") << "$d" << i << " using 1:2 with " << fig.series[i].style
          << (fig.series[i].title.empty() ? std::string(" notitle")
                                          : " title " + quote(fig.series[i].title));
        any = true;
    }
    if (!any) g << "NaN notitle";
    g << "\nunset output\n";

    // gnuplot's own messages go to stderr; stdout is never a PNG stream (output set above).
    FILE* p = popen("gnuplot > /dev/null", "w");
    if (!p)
    {
        if (error) *error = "cannot run gnuplot";
        return false;
    }
    const std::string script = g.str();
    std::fwrite(script.data(), 1, script.size(), p);
    const int rc = pclose(p);
    if (rc != 0)
    {
        if (error)
            *error = "gnuplot failed (exit " + std::to_string(rc) +
                     "); is it installed? (apt-get install gnuplot-nox)";
        return false;
    }
    return true;
}

Series cdf(std::vector<double> v, const std::string& title)
{
    std::sort(v.begin(), v.end());
    Series s;
    s.title = title;
    s.style = "steps lw 2";
    for (size_t i = 0; i < v.size(); ++i)
    {
        s.x.push_back(v[i]);
        s.y.push_back(double(i + 1) / v.size());
    }
    return s;
}

Series ellipse(
    double cx, double cy, double sxx, double sxy, double syy, double k, const std::string& title,
    const std::string& style)
{
    // Eigen-decomposition of the symmetric 2×2 covariance.
    const double tr = sxx + syy, det = sxx * syy - sxy * sxy;
    const double disc = std::sqrt(std::max(0.0, tr * tr / 4 - det));
    const double l1 = std::max(0.0, tr / 2 + disc), l2 = std::max(0.0, tr / 2 - disc);
    const double ang = 0.5 * std::atan2(2 * sxy, sxx - syy);
    Series s;
    s.title = title;
    s.style = style;
    for (int i = 0; i <= 72; ++i)
    {
        const double a = 2 * M_PI * i / 72;
        const double u = k * std::sqrt(l1) * std::cos(a), v = k * std::sqrt(l2) * std::sin(a);
        s.x.push_back(cx + u * std::cos(ang) - v * std::sin(ang));
        s.y.push_back(cy + u * std::sin(ang) + v * std::cos(ang));
    }
    return s;
}

}  // namespace mrpt_wifi::localization::plot
