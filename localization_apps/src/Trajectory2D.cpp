/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/poses/CPose2D.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/localization/TransmitterMap.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace mrpt_wifi::localization
{
using mrpt::math::TPoint2D;
using mrpt::math::TPose2D;

namespace
{
/** Yaw of a quaternion (rotation about z dominates for a planar robot). */
double planarYaw(double qx, double qy, double qz, double qw)
{
    return std::atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz));
}

/** Rows sorted by time into a trajectory; a repeated timestamp is an error naming the file. */
Trajectory2D sortedTrajectory(
    const std::string& path, std::vector<std::pair<double, TPose2D>>& rows)
{
    std::stable_sort(
        rows.begin(), rows.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    Trajectory2D out;
    for (size_t i = 0; i < rows.size(); ++i)
    {
        if (i && rows[i].first == rows[i - 1].first)
            throw std::runtime_error(
                path + ": duplicate timestamp " + std::to_string(rows[i].first));
        out.push_back(rows[i].first, rows[i].second);
    }
    return out;
}
}  // namespace

Trajectory2D Trajectory2D::fromTumFile(const std::string& path)
{
    std::ifstream f(path);
    if (!f) throw std::runtime_error(path + ": cannot open TUM trajectory");
    std::vector<std::pair<double, TPose2D>> rows;
    std::string line;
    int lineNo = 0;
    while (std::getline(f, line))
    {
        ++lineNo;
        const auto b = line.find_first_not_of(" \t\r");
        if (b == std::string::npos || line[b] == '#') continue;
        std::istringstream is(line);
        double v[8];
        for (double& x : v)
            if (!(is >> x))
                throw std::runtime_error(
                    path + ":" + std::to_string(lineNo) + ": expected 't x y z qx qy qz qw'");
        rows.emplace_back(v[0], TPose2D(v[1], v[2], planarYaw(v[4], v[5], v[6], v[7])));
    }
    return sortedTrajectory(path, rows);
}

Trajectory2D Trajectory2D::fromWsrCsv(const std::string& path)
{
    std::ifstream f(path);
    if (!f) throw std::runtime_error(path + ": cannot open trajectory");
    std::vector<std::pair<double, TPose2D>> rows;
    std::string line;
    int lineNo = 0;
    while (std::getline(f, line))
    {
        ++lineNo;
        if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
        std::vector<double> v;
        std::istringstream is(line);
        std::string field;
        while (std::getline(is, field, ','))
        {
            if (field.find_first_not_of(" \t\r") == std::string::npos) continue;
            try
            {
                size_t used = 0;
                v.push_back(std::stod(field, &used));
                // stod takes "nan" and "inf": a pose must be a finite number.
                if (field.find_first_not_of(" \t\r", used) != std::string::npos ||
                    !std::isfinite(v.back()))
                    throw std::invalid_argument(field);
            }
            catch (const std::exception&)
            {
                throw std::runtime_error(
                    path + ":" + std::to_string(lineNo) + ": '" + field +
                    "' is not a finite number");
            }
        }
        if (v.size() == 5)  // motion capture: t, (unused), x, y, z; no heading recorded
            rows.emplace_back(v[0], TPose2D(v[2], v[3], 0.0));
        else if (v.size() >= 9)  // ROS odometry: sec, nsec, x, y, z, qx, qy, qz, qw, twist...
            rows.emplace_back(
                v[0] + 1e-9 * v[1], TPose2D(v[2], v[3], planarYaw(v[5], v[6], v[7], v[8])));
        else
            throw std::runtime_error(
                path + ":" + std::to_string(lineNo) + ": " + std::to_string(v.size()) +
                " fields; expected 5 (t, -, x, y, z: motion capture) or at least 9 (sec, nsec, "
                "x, y, z, qx, qy, qz, qw: odometry / tracking camera)");
    }
    if (rows.empty()) throw std::runtime_error(path + ": no trajectory rows");
    return sortedTrajectory(path, rows);
}

Trajectory2D Trajectory2D::fromFile(const std::string& path)
{
    const bool csv = path.size() >= 4 && path.compare(path.size() - 4, 4, ".csv") == 0;
    return csv ? fromWsrCsv(path) : fromTumFile(path);
}

void Trajectory2D::saveTum(const std::string& path, const std::string& comment) const
{
    std::ofstream f(path);
    if (!f) throw std::runtime_error(path + ": cannot write");
    f << "# " << (comment.empty() ? "trajectory" : comment) << ", TUM: t x y z qx qy qz qw\n";
    for (size_t i = 0; i < size(); ++i) f << tumLine(t[i], poses[i]);
}

std::string Trajectory2D::tumLine(double time, const TPose2D& p)
{
    char buf[256];
    std::snprintf(
        buf, sizeof(buf), "%.6f %.6f %.6f 0 0 0 %.9f %.9f\n", time, p.x, p.y, std::sin(p.phi / 2),
        std::cos(p.phi / 2));
    return buf;
}

bool Trajectory2D::interpolate(double time, TPose2D& out, double maxGap) const
{
    if (t.empty() || time < t.front() || time > t.back()) return false;
    const auto it = std::lower_bound(t.begin(), t.end(), time);
    const size_t i1 = size_t(it - t.begin());
    if (t[i1] == time)
    {
        out = poses[i1];
        return true;
    }
    const size_t i0 = i1 - 1;
    const double dt = t[i1] - t[i0];
    if (dt > maxGap) return false;
    const double a = (time - t[i0]) / dt;
    const auto &p0 = poses[i0], &p1 = poses[i1];
    out.x = p0.x + a * (p1.x - p0.x);
    out.y = p0.y + a * (p1.y - p0.y);
    out.phi = wrapToPi(p0.phi + a * wrapToPi(p1.phi - p0.phi));
    return true;
}

std::string ErrorStats::asString(const char* unit) const
{
    char buf[256];
    std::snprintf(
        buf, sizeof(buf), "n=%zu  rmse=%.3f %s  mean=%.3f  median=%.3f  p90=%.3f  max=%.3f", count,
        rmse, unit, mean, median, p90, max);
    return buf;
}

ErrorStats computeStats(std::vector<double> e)
{
    ErrorStats s;
    s.count = e.size();
    if (e.empty()) return s;
    std::sort(e.begin(), e.end());
    double sq = 0, sum = 0;
    for (double v : e) sq += v * v, sum += v;
    s.rmse = std::sqrt(sq / e.size());
    s.mean = sum / e.size();
    auto quantile = [&](double q)
    {
        const double pos = q * (e.size() - 1);
        const size_t i = size_t(pos);
        return i + 1 < e.size() ? e[i] + (pos - i) * (e[i + 1] - e[i]) : e[i];
    };
    s.median = quantile(0.5);
    s.p90 = quantile(0.9);
    s.max = e.back();
    return s;
}

namespace
{
/** Umeyama's least-squares similarity b ≈ s·R·a + t (Eigen's), scale fixed at 1 unless asked. */
Similarity2D umeyama2D(const std::vector<TPoint2D>& a, const std::vector<TPoint2D>& b, bool scale)
{
    if (a.size() != b.size() || a.size() < 2)
        throw std::invalid_argument("alignRigid2D / alignSimilarity2D: bad input");
    Eigen::Matrix2Xd A(2, a.size()), B(2, b.size());
    for (size_t i = 0; i < a.size(); ++i)
        A.col(Eigen::Index(i)) << a[i].x, a[i].y, B.col(Eigen::Index(i)) << b[i].x, b[i].y;
    const Eigen::Matrix3d T = Eigen::umeyama(A, B, scale);
    Similarity2D r;
    r.scale = scale ? T.block<2, 2>(0, 0).col(0).norm() : 1.0;
    r.pose = TPose2D(T(0, 2), T(1, 2), std::atan2(T(1, 0), T(0, 0)));
    return r;
}
}  // namespace

TPose2D alignRigid2D(const std::vector<TPoint2D>& a, const std::vector<TPoint2D>& b)
{
    return umeyama2D(a, b, false).pose;
}

Similarity2D alignSimilarity2D(const std::vector<TPoint2D>& a, const std::vector<TPoint2D>& b)
{
    return umeyama2D(a, b, true);
}

AteResult absoluteTrajectoryError(
    const Trajectory2D& est, const Trajectory2D& truth, bool align, bool correctScale)
{
    AteResult r;
    std::vector<TPoint2D> a, b;
    for (size_t i = 0; i < est.size(); ++i)
    {
        TPose2D gt;
        if (!truth.interpolate(est.t[i], gt, 0.5))
        {
            r.unmatched++;
            continue;
        }
        a.emplace_back(est.poses[i].x, est.poses[i].y);
        b.emplace_back(gt.x, gt.y);
        r.times.push_back(est.t[i]);
    }
    if (a.size() < 2)
        throw std::runtime_error(
            "ATE: the estimate and the ground truth don't overlap in time (" +
            std::to_string(a.size()) + " poses matched)");
    if (align)
    {
        const auto sim = umeyama2D(a, b, correctScale);
        r.alignment = sim.pose;
        r.scale = sim.scale;
    }
    const mrpt::poses::CPose2D T(r.alignment);
    for (size_t i = 0; i < a.size(); ++i)
    {
        const auto p = T.composePoint(a[i] * r.scale);
        r.errors.push_back(std::hypot(p.x - b[i].x, p.y - b[i].y));
    }
    r.stats = computeStats(r.errors);
    return r;
}

}  // namespace mrpt_wifi::localization
