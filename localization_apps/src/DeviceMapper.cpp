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
    const size_t stride = std::max<size_t>(1, rays.size() / o.maxGridRays);
    double best = -1e300, bx = 0, by = 0;
    for (double x = xmin; x <= xmax + 1e-9; x += o.gridStep_m)
        for (double y = ymin; y <= ymax + 1e-9; y += o.gridStep_m)
        {
            double ll = 0;
            for (size_t i = 0; i < rays.size(); i += stride)
            {
                const auto& r = rays[i];
                const double pred = wrapToPi(std::atan2(y - r.y, x - r.x) - r.sensorYaw);
                ll += o.model.logLikelihood(
                    pred, r.aoa, r.ambiguous, r.mirror, o.model.sigma(r.sigma));
            }
            if (ll > best) best = ll, bx = x, by = y;
        }

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
            cells.emplace(
                long(std::floor(rays[i].x / o.decorrelation_m)),
                long(std::floor(rays[i].y / o.decorrelation_m)));
            chi2 += (res[i] / sg) * (res[i] / sg);
        }
        if (d.inliers > 0 && !cells.empty())
        {
            d.covInflation = std::max(1.0, chi2 / d.inliers) * double(d.inliers) / cells.size();
            for (double& cv : d.cov) cv *= d.covInflation;
        }
    }
    std::nth_element(res.begin(), res.begin() + long(res.size() / 2), res.end());
    d.medianResidual_deg = mrpt::RAD2DEG(res[res.size() / 2]);
    d.baseline_deg = first ? 0 : mrpt::RAD2DEG(dmax - dmin);
    d.localized = sum.IsSolutionUsable() && d.inliers >= o.minRays;
    if (!d.localized && d.note.empty())
        d.note = "too few consistent bearings (" + std::to_string(d.inliers) + " inliers)";
    else if (d.localized && d.baseline_deg < 10)
        d.note = "weak geometry: rays span only " + std::to_string(int(d.baseline_deg)) + " deg";
    return d;
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
