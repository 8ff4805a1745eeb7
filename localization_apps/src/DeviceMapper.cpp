/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/bits_math.h>
#include <mrpt_wifi/localization/DeviceMapper.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <stdexcept>

#include "BearingResiduals.h"

namespace mrpt_wifi::localization
{
std::map<MacAddress, std::vector<BearingRay>> raysFromBearings(
    const std::vector<BearingRecord>& bearings, const Trajectory2D& traj, InputWarnings* warn,
    double maxGap)
{
    std::map<MacAddress, std::vector<BearingRay>> out;
    for (const auto& b : bearings)
    {
        if (!b.hasAoa) continue;
        mrpt::math::TPose2D robot;
        if (!traj.interpolate(b.t, robot, maxGap))
        {
            if (warn) warn->outsideTrajectory++;
            continue;
        }
        const auto s = sensorWorldPose(robot, b.sensorPose);
        BearingRay r;
        r.t = b.t, r.x = s.x, r.y = s.y, r.sensorYaw = s.phi;
        r.aoa = b.aoa, r.mirror = b.aoaMirror, r.ambiguous = b.aoaAmbiguous, r.sigma = b.aoaStd;
        out[b.transmitter].push_back(r);
    }
    return out;
}

void addOdometryDrift(
    std::map<MacAddress, std::vector<BearingRay>>& rays, const Trajectory2D& traj,
    const OdometryDrift& drift)
{
    if (traj.empty()) return;
    // Per trajectory pose i: distance travelled s_i and the heading walk's effect on the
    // position, ∫₀^{s_i} |p_i − p(s')|² ds' (a heading error picked up at s' rotates everything
    // driven after it: on a loop back to the start it cancels), accumulated in O(N) from
    // S0 = ∫ds, S1 = ∫p ds, S2 = ∫|p|² ds (positions relative to the first pose).
    const size_t n = traj.size();
    std::vector<double> arc(n, 0.0), headingVar(n, 0.0);
    double S0 = 0, S1x = 0, S1y = 0, S2 = 0;
    const double x0 = traj.poses.front().x, y0 = traj.poses.front().y;
    for (size_t i = 1; i < n; ++i)
    {
        const double ax = traj.poses[i - 1].x - x0, ay = traj.poses[i - 1].y - y0;
        const double bx = traj.poses[i].x - x0, by = traj.poses[i].y - y0;
        const double ds = std::hypot(bx - ax, by - ay);
        const double mx = 0.5 * (ax + bx), my = 0.5 * (ay + by);
        S0 += ds, S1x += ds * mx, S1y += ds * my, S2 += ds * (mx * mx + my * my);
        arc[i] = S0;
        headingVar[i] = std::max(0.0, (bx * bx + by * by) * S0 - 2 * (bx * S1x + by * S1y) + S2);
    }
    const auto at = [&](const std::vector<double>& v, double t)
    {
        if (t <= traj.t.front()) return v.front();
        if (t >= traj.t.back()) return v.back();
        const size_t i = size_t(std::upper_bound(traj.t.begin(), traj.t.end(), t) - traj.t.begin());
        const double f = (t - traj.t[i - 1]) / (traj.t[i] - traj.t[i - 1]);
        return v[i - 1] + f * (v[i] - v[i - 1]);
    };
    const double sxy2 = drift.sigmaXY_perSqrtM * drift.sigmaXY_perSqrtM,
                 syaw2 = drift.sigmaYaw_perSqrtM * drift.sigmaYaw_perSqrtM;
    for (auto& [mac, list] : rays)
        for (auto& r : list)
        {
            r.poseStdYaw = std::sqrt(syaw2 * at(arc, r.t));
            // Per axis: the heading term spreads over both axes.
            r.poseStdXY = std::sqrt(sxy2 * at(arc, r.t) + 0.5 * syaw2 * at(headingVar, r.t));
        }
}

double mahalanobis2(double xx, double xy, double yy, double ex, double ey)
{
    const double det = xx * yy - xy * xy;
    if (!(det > 0) || !(xx > 0)) return INFINITY;
    return (yy * ex * ex - 2 * xy * ex * ey + xx * ey * ey) / det;
}

std::pair<long, long> decorrelationCell(double x, double y, double size)
{
    return {long(std::floor(x / size)), long(std::floor(y / size))};
}

void BearingDecorrelation::add(const MacAddress& transmitter, double x, double y)
{
    if (!(cell_m_ > 0)) return;
    auto& [count, cells] = seen_[transmitter];
    ++count;
    cells.insert(decorrelationCell(x, y, cell_m_));
}

double BearingDecorrelation::factor(const MacAddress& transmitter) const
{
    const auto it = seen_.find(transmitter);
    if (it == seen_.end()) return 1.0;
    const auto& [count, cells] = it->second;
    return std::sqrt(double(count) / double(cells.size()));
}

DeviceEstimate triangulateDevice(const std::vector<BearingRay>& rays, const DeviceMapOptions& o)
{
    DeviceEstimate d;
    d.rays = rays.size();
    if (rays.size() < o.minRays)
    {
        d.note = "only " + std::to_string(rays.size()) + " bearings (need " +
                 std::to_string(o.minRays) + ")";
        return d;
    }
    double xmin = o.xmin, xmax = o.xmax, ymin = o.ymin, ymax = o.ymax;
    if (!o.boundsGiven)
    {
        xmin = ymin = 1e300, xmax = ymax = -1e300;
        for (const auto& r : rays)
        {
            xmin = std::min(xmin, r.x), xmax = std::max(xmax, r.x);
            ymin = std::min(ymin, r.y), ymax = std::max(ymax, r.y);
        }
        xmin -= o.margin_m, ymin -= o.margin_m, xmax += o.margin_m, ymax += o.margin_m;
    }

    // 1) Global search: the mixture log-likelihood over a grid. Robust to outliers and to the
    //    mirror ambiguity (both candidates enter the mixture), no initial guess needed.
    //    Coarse to fine, so that its cost does not grow with the area: a grid of at most
    //    kCoarseCells cells per side, then around its best few cells grids 4 times finer down
    //    to gridStep_m. On a grid of step c a ray at range d can be c/d off the cell's best
    //    point: its σ grows by that much, so the cell holding the device still scores well.
    const size_t stride = std::max<size_t>(1, rays.size() / o.maxGridRays);
    std::vector<const BearingRay*> gridRays;
    for (size_t i = 0; i < rays.size(); i += stride) gridRays.push_back(&rays[i]);
    const auto score = [&](double x, double y, double step, size_t every)
    {
        const bool blurred = step > o.gridStep_m + 1e-12;
        double ll = 0;
        for (size_t i = 0; i < gridRays.size(); i += every)
        {
            const BearingRay* r = gridRays[i];
            const double dx = x - r->x, dy = y - r->y;
            const double pred = wrapToPi(std::atan2(dy, dx) - r->sensorYaw);
            double sg = o.model.sigma(r->sigma);
            if (blurred)
            {
                const double blur = 0.7 * step / std::max(step, std::hypot(dx, dy));
                sg = std::sqrt(sg * sg + blur * blur);
            }
            ll += o.model.logLikelihood(pred, r->aoa, r->ambiguous, r->mirror, sg);
        }
        return ll;
    };
    struct Cell
    {
        double ll, x, y;
    };
    constexpr double kCoarseCells = 48;
    constexpr size_t kModes = 4, kCoarseRays = 100;
    double step = std::max(o.gridStep_m, std::max(xmax - xmin, ymax - ymin) / kCoarseCells);
    // Blurred as it is, the coarse grid needs fewer rays than the fine ones (only when it is
    // coarser than gridStep_m: a room keeps its one full grid).
    const size_t coarseEvery =
        step > o.gridStep_m + 1e-12 ? std::max<size_t>(1, gridRays.size() / kCoarseRays) : 1;
    std::vector<Cell> cells;
    for (double x = xmin; x <= xmax + 1e-9; x += step)
        for (double y = ymin; y <= ymax + 1e-9; y += step)
            cells.push_back({score(x, y, step, coarseEvery), x, y});
    // The best few cells at least two cells apart: each refined on finer grids.
    const auto bestDistinct = [&](std::vector<Cell>& all, double apart)
    {
        std::sort(all.begin(), all.end(), [](const Cell& a, const Cell& b) { return a.ll > b.ll; });
        std::vector<Cell> modes;
        for (const auto& c : all)
        {
            if (modes.size() >= kModes) break;
            bool near = false;
            for (const auto& m : modes) near |= std::hypot(c.x - m.x, c.y - m.y) < apart;
            if (!near) modes.push_back(c);
        }
        return modes;
    };
    std::vector<Cell> modes = bestDistinct(cells, 2 * step + 1e-9);
    while (step > o.gridStep_m + 1e-12)
    {
        const double fine = std::max(o.gridStep_m, step / 4);
        std::vector<Cell> refined;
        for (const auto& m : modes)
        {
            const int n = int(std::ceil(step / fine));
            for (int i = -n; i <= n; ++i)
                for (int j = -n; j <= n; ++j)
                {
                    const double x = m.x + i * fine, y = m.y + j * fine;
                    refined.push_back({score(x, y, fine, 1), x, y});
                }
        }
        step = fine;
        modes = bestDistinct(refined, 2 * step + 1e-9);
    }
    const double bx = modes.front().x, by = modes.front().y;

    // 2) Refinement with all rays and a robust loss.
    double p[2] = {bx, by};
    ceres::Problem problem;
    for (const auto& r : rays)
    {
        auto* f = new ceres::AutoDiffCostFunction<detail::PointAoaResidual, 1, 2>(
            new detail::PointAoaResidual{
                r.x, r.y, r.sensorYaw, r.aoa, r.mirror, o.model.sigma(r.sigma), r.ambiguous});
        problem.AddResidualBlock(f, detail::makeLoss(o.loss, o.lossScale), p);
    }
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::DENSE_QR;
    so.max_num_iterations = 50;
    ceres::Solver::Summary sum;
    ceres::Solve(so, &problem, &sum);
    d.x = p[0], d.y = p[1];

    // 3) Uncertainty at the solution.
    ceres::Covariance::Options co;
    ceres::Covariance cov(co);
    std::vector<std::pair<const double*, const double*>> blocks = {{p, p}};
    double c[4] = {0, 0, 0, 0};
    if (cov.Compute(blocks, &problem) && cov.GetCovarianceBlock(p, p, c))
        d.cov[0] = c[0], d.cov[1] = c[1], d.cov[2] = c[3];
    else
        d.note = "covariance not available (degenerate geometry)";

    std::vector<double> res;
    double dmin = 1e9, dmax = -1e9, ref = 0;
    bool first = true;
    for (const auto& r : rays)
    {
        const double pred = std::atan2(d.y - r.y, d.x - r.x) - r.sensorYaw;
        const double e = std::abs(detail::closestCandidate(pred, r.aoa, r.ambiguous, r.mirror));
        res.push_back(e);
        if (e < o.inlierSigmas * o.model.sigma(r.sigma))
        {
            d.inliers++;
            // Directions from the device to inlier rays' origins: their spread is the baseline.
            const double dir = std::atan2(r.y - d.y, r.x - d.x);
            if (first) ref = dir, first = false;
            const double rel = wrapToPi(dir - ref);
            dmin = std::min(dmin, rel), dmax = std::max(dmax, rel);
        }
    }
    {
        std::set<std::pair<long, long>> cells;
        double chi2 = 0;
        for (size_t i = 0; i < rays.size(); ++i)
        {
            const double sg = o.model.sigma(rays[i].sigma);
            if (res[i] >= o.inlierSigmas * sg) continue;
            if (o.decorrelation_m > 0)
                cells.insert(decorrelationCell(rays[i].x, rays[i].y, o.decorrelation_m));
            else
                cells.emplace(long(i), 0L);  // every bearing independent
            chi2 += (res[i] / sg) * (res[i] / sg);
        }
        if (d.inliers > 0 && !cells.empty())
        {
            d.covInflation = std::max(1.0, chi2 / d.inliers) * double(d.inliers) / cells.size();
            for (double& cv : d.cov) cv *= d.covInflation;
        }
    }
    if (o.includePoseUncertainty && d.inliers > 0)
    {
        // Odometry drift moves every ray of a stretch together: the device moves with it.
        double var = 0;
        for (size_t i = 0; i < rays.size(); ++i)
        {
            const auto& r = rays[i];
            if (res[i] >= o.inlierSigmas * o.model.sigma(r.sigma)) continue;
            const double range = std::hypot(d.x - r.x, d.y - r.y);
            var += r.poseStdXY * r.poseStdXY + range * range * r.poseStdYaw * r.poseStdYaw;
        }
        var /= double(d.inliers);
        d.poseStd_m = std::sqrt(var);
        d.cov[0] += var, d.cov[2] += var;
    }
    d.medianResidual_deg = mrpt::RAD2DEG(detail::median(std::move(res)));
    d.baseline_deg = first ? 0 : mrpt::RAD2DEG(dmax - dmin);
    d.localized = sum.IsSolutionUsable() && d.inliers >= o.minRays;
    if (!d.localized && d.note.empty())
        d.note = "too few consistent bearings (" + std::to_string(d.inliers) + " inliers)";
    else if (d.localized && d.baseline_deg < 10)
        d.note = "weak geometry: rays span only " + std::to_string(int(d.baseline_deg)) + " deg";
    return d;
}

DeviceEstimate locateObserver(const std::vector<BearingToKnown>& bearings, DeviceMapOptions o)
{
    std::vector<BearingRay> rays;
    for (const auto& b : bearings)
    {
        BearingRay r;
        r.x = b.transmitter.x, r.y = b.transmitter.y;
        r.aoa = wrapToPi(b.bearing_rad + M_PI);
        r.sigma = b.sigma_rad;
        rays.push_back(r);
    }
    o.minRays = std::min<size_t>(o.minRays, 2);
    return triangulateDevice(rays, o);
}

void saveDeviceCsv(const std::string& path, const std::vector<DeviceEstimate>& devs)
{
    std::ofstream f(path);
    if (!f) throw std::runtime_error(path + ": cannot write");
    f << "mac,name,localized,x_m,y_m,cov_xx,cov_xy,cov_yy,bearings,inliers,"
         "median_residual_deg,baseline_deg,note\n";
    for (const auto& d : devs)
        f << d.mac.asString() << ',' << d.name << ',' << (d.localized ? 1 : 0) << ',' << d.x << ','
          << d.y << ',' << d.cov[0] << ',' << d.cov[1] << ',' << d.cov[2] << ',' << d.rays << ','
          << d.inliers << ',' << d.medianResidual_deg << ',' << d.baseline_deg << ",\"" << d.note
          << "\"\n";
}

void saveDeviceYaml(const std::string& path, const std::vector<DeviceEstimate>& devs)
{
    TransmitterMap m;
    for (const auto& d : devs)
    {
        if (!d.localized) continue;
        KnownTransmitter t;
        t.mac = d.mac;
        t.name = d.name.empty() ? d.mac.asString() : d.name;
        t.pose = mrpt::math::TPose2D(d.x, d.y, 0);
        t.array = ArrayGeometry::fromElements({});
        m.add(t);
    }
    std::ofstream f(path);
    if (!f) throw std::runtime_error(path + ": cannot write");
    f << "# devices mapped by wifi-iot-map (positions [m]; yaw unknown, set to 0)\n"
      << m.asYamlText();
}

}  // namespace mrpt_wifi::localization
