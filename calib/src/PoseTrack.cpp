/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/poses/CPose2D.h>
#include <mrpt_wifi/calib/PoseTrack.h>
#include <mrpt_wifi/obs/AntennaArray.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace mrpt_wifi::calib
{
void PoseTrack::add(double t_s, const mrpt::math::TPose2D& pose)
{
    if (!samples_.empty() && t_s < samples_.back().t) sorted_ = false;
    samples_.push_back({t_s, pose});
}

void PoseTrack::ensureSorted() const
{
    if (sorted_) return;
    std::stable_sort(
        samples_.begin(), samples_.end(),
        [](const Sample& a, const Sample& b) { return a.t < b.t; });
    sorted_ = true;
}

double PoseTrack::startTime() const
{
    ensureSorted();
    return samples_.empty() ? 0 : samples_.front().t;
}

double PoseTrack::endTime() const
{
    ensureSorted();
    return samples_.empty() ? 0 : samples_.back().t;
}

bool PoseTrack::at(double t_s, mrpt::math::TPose2D& out) const
{
    ensureSorted();
    if (samples_.empty() || t_s < samples_.front().t || t_s > samples_.back().t) return false;
    auto hi = std::lower_bound(
        samples_.begin(), samples_.end(), t_s, [](const Sample& s, double t) { return s.t < t; });
    if (hi->t == t_s)
    {
        out = hi->pose;
        return true;
    }
    const auto lo = hi - 1;
    const double dt = hi->t - lo->t;
    if (dt > maxGap_s) return false;
    const double a = (t_s - lo->t) / dt;
    out.x = lo->pose.x + a * (hi->pose.x - lo->pose.x);
    out.y = lo->pose.y + a * (hi->pose.y - lo->pose.y);
    out.phi = wrapAngle(lo->pose.phi + a * wrapAngle(hi->pose.phi - lo->pose.phi));
    return true;
}

PoseTrack PoseTrack::transformed(const mrpt::math::TPose2D& origin) const
{
    PoseTrack r;
    r.maxGap_s = maxGap_s;
    const mrpt::poses::CPose2D o(origin);
    for (const auto& s : samples_) r.add(s.t, (o + mrpt::poses::CPose2D(s.pose)).asTPose());
    return r;
}

PoseTrack PoseTrack::fromTumFile(const std::string& path)
{
    std::ifstream f(path);
    if (!f) throw std::runtime_error("cannot open trajectory file '" + path + "'");
    PoseTrack track;
    std::string line;
    int lineNo = 0;
    while (std::getline(f, line))
    {
        ++lineNo;
        const auto first = line.find_first_not_of(" \t\r");
        if (first == std::string::npos || line[first] == '#') continue;
        std::istringstream is(line);
        double t, x, y, z, qx, qy, qz, qw;
        if (!(is >> t >> x >> y >> z >> qx >> qy >> qz >> qw))
            throw std::runtime_error(
                path + ":" + std::to_string(lineNo) +
                ": expected 8 numbers 't x y z qx qy qz qw' (TUM format)");
        const double yaw = std::atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz));
        track.add(t, mrpt::math::TPose2D(x, y, yaw));
    }
    if (track.empty()) throw std::runtime_error("trajectory file '" + path + "' has no poses");
    return track;
}

}  // namespace mrpt_wifi::calib
