/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/bits_math.h>
#include <mrpt/math/wrap2pi.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/system/CTicTac.h>
#include <mrpt_wifi/localization/BearingLikelihood.h>
#include <mrpt_wifi/localization/CWiFiBearingMap.h>
#include <mrpt_wifi/localization/IniValues.h>
#include <mrpt_wifi/localization/WindowSmoother.h>
#include <mrpt_wifi/obs/ConfigKeys.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "BearingResiduals.h"

namespace mrpt_wifi::localization
{
using mrpt::math::TPose2D;
using mrpt::poses::CPose2D;

GraphSlamOptions WindowSmootherOptions::defaultGraph()
{
    GraphSlamOptions g;  // apsKnown and no estimated-AP start: the constructor sets them
    g.threads = 1;
    g.maxIterations = 100;
    return g;
}

void WindowSmootherOptions::loadFromConfigFile(
    const mrpt::config::CConfigFileBase& c, const std::string& s)
{
    config::requireKnownKeys(c, s, config::sectionKeys("WindowSmoother"));
    requireIniNumbers(
        c, s,
        {"window_s", "min_window_s", "solve_period_s", "max_median_whitened_residual",
         "max_filter_spread_m", "max_recent_residual_deg", "node_period_s", "odometry_scale_std",
         "odometry_yaw_drift_deg_per_m", "min_std_deg", "bearing_decorrelation_m", "max_iterations",
         "track_window_s", "track_switch_cost", "track_restart_headings"});
    requireIniBools(c, s, {"enabled", "without_odometry"});
    enabled = c.read_bool(s, "enabled", enabled);
    window_s = c.read_double(s, "window_s", window_s);
    minWindow_s = c.read_double(s, "min_window_s", minWindow_s);
    solvePeriod_s = c.read_double(s, "solve_period_s", solvePeriod_s);
    maxMedianWhitenedResidual =
        c.read_double(s, "max_median_whitened_residual", maxMedianWhitenedResidual);
    maxFilterSpread_m = c.read_double(s, "max_filter_spread_m", maxFilterSpread_m);
    maxRecentResidual_rad = mrpt::DEG2RAD(
        c.read_double(s, "max_recent_residual_deg", mrpt::RAD2DEG(maxRecentResidual_rad)));

    graph.nodePeriod_s = c.read_double(s, "node_period_s", graph.nodePeriod_s);
    graph.odoScaleStd = c.read_double(s, "odometry_scale_std", graph.odoScaleStd);
    graph.odoYawDriftStd_radPerM = mrpt::DEG2RAD(c.read_double(
        s, "odometry_yaw_drift_deg_per_m", mrpt::RAD2DEG(graph.odoYawDriftStd_radPerM)));
    graph.minStd_rad =
        mrpt::DEG2RAD(c.read_double(s, "min_std_deg", mrpt::RAD2DEG(graph.minStd_rad)));
    graph.loss = c.read_string(s, "loss", graph.loss);
    graph.bearingDecorrelation_m =
        c.read_double(s, "bearing_decorrelation_m", graph.bearingDecorrelation_m);
    graph.maxIterations = c.read_int(s, "max_iterations", graph.maxIterations);
    withoutOdometry = c.read_bool(s, "without_odometry", withoutOdometry);
    trackWindow_s = c.read_double(s, "track_window_s", trackWindow_s);
    trackSwitchCost = c.read_double(s, "track_switch_cost", trackSwitchCost);
    trackRestartHeadings = c.read_int(s, "track_restart_headings", trackRestartHeadings);
    track.loadFromConfigFile(c, s);
    if (!(window_s > 0) || !(minWindow_s >= 0) || !(minWindow_s <= window_s) ||
        !(solvePeriod_s > 0) || !(maxMedianWhitenedResidual > 0) || !(maxFilterSpread_m > 0) ||
        !(maxRecentResidual_rad > 0) || !(graph.nodePeriod_s > 0) || !(graph.odoScaleStd >= 0) ||
        !(graph.odoYawDriftStd_radPerM >= 0) || !(graph.minStd_rad > 0) ||
        !(trackWindow_s >= minWindow_s) || !(trackWindow_s >= 2 * track.nodePeriod_s) ||
        !(trackSwitchCost >= 0) || trackRestartHeadings < 0)
        throw std::invalid_argument(
            "[" + s +
            "]: window_s, solve_period_s, max_median_whitened_residual, max_filter_spread_m, "
            "max_recent_residual_deg, "
            "node_period_s and min_std_deg must be > 0, min_window_s in [0, window_s], "
            "track_window_s at least min_window_s and two track_node_period_s, "
            "track_switch_cost and track_restart_headings >= 0, "
            "odometry_scale_std and odometry_yaw_drift_deg_per_m >= 0");
    if (graph.loss != "cauchy" && graph.loss != "huber" && graph.loss != "none")
        throw std::invalid_argument(
            "[" + s + "] loss = " + graph.loss + ": expected cauchy, huber or none");
}

std::string WindowSmootherOptions::asString() const
{
    if (!enabled) return "off";
    std::ostringstream o;
    o << "window " << window_s << " s, a solve every " << solvePeriod_s
      << " s, used if the median |residual|/sigma <= " << maxMedianWhitenedResidual
      << " and the last 2 s' median |AoA residual| <= " << mrpt::RAD2DEG(maxRecentResidual_rad)
      << " deg";
    if (withoutOdometry)
        o << "; without odometry a " << trackWindow_s << " s track, a node every "
          << track.nodePeriod_s << " s, speed change sigma " << track.accelStd_mps2
          << " m/s^2, turn " << mrpt::RAD2DEG(track.turnAccelStd_radps2) << " deg/s^2, sideways "
          << track.lateralStd_m << " m per node" << (track.forwardOnly ? ", forward only" : "")
          << (trackRestartHeadings > 0 ? ", after a restart also from the last accepted pose at " +
                                             std::to_string(trackRestartHeadings) + " headings"
                                       : std::string());
    return o.str();
}

WindowSmoother::WindowSmoother(const WindowSmootherOptions& options, const TransmitterMap& aps)
    : opts_(options), aps_(aps)
{
    opts_.graph.apsKnown = true;
    opts_.graph.alignEstimatedAps = false;
}

void WindowSmoother::addOdometry(double t, const TPose2D& odometry)
{
    if (!opts_.enabled || (!odometry_.empty() && t <= odometry_.back().first)) return;
    odometry_.emplace_back(t, odometry);
    forgetBefore(t - opts_.window_s - 1);
}

void WindowSmoother::addBearing(const BearingRecord& b)
{
    if (!opts_.enabled || !aps_.find(b.transmitter)) return;
    bearings_.push_back(b);
    forgetBefore(b.t - opts_.window_s - 1);
}

void WindowSmoother::forgetBefore(double t)
{
    // Keeps memory bounded also while update() is not called (no odometry yet, live).
    while (odometry_.size() > 1 && odometry_[1].first <= t) odometry_.pop_front();
    while (!bearings_.empty() && bearings_.front().t < t) bearings_.pop_front();
    while (!filterEstimates_.empty() && filterEstimates_.front().first < t)
        filterEstimates_.pop_front();
}

const std::pair<double, TPose2D>* WindowSmoother::odometryAt(double t) const
{
    const std::pair<double, TPose2D>* found = nullptr;
    for (auto it = odometry_.rbegin(); it != odometry_.rend() && !found; ++it)
        if (it->first <= t) found = &*it;
    return found;
}

std::optional<TPose2D> WindowSmoother::update(
    double t, const TPose2D& filterEstimate, const std::function<double()>& filterSpread_m)
{
    if (!opts_.enabled) return std::nullopt;
    if (t < lastSolve_t_)  // a new run
        solved_.reset(), track_.reset(), restartPose_.reset(), lastSolve_t_ = -1e300;
    const bool tracking = odometry_.empty() && opts_.withoutOdometry;
    if (tracking && (filterEstimates_.empty() || t > filterEstimates_.back().first))
    {
        filterEstimates_.emplace_back(t, filterEstimate);
        forgetBefore(t - std::max(opts_.window_s, opts_.trackWindow_s) - 1);
    }
    if (t - lastSolve_t_ >= opts_.solvePeriod_s - 1e-9)
    {
        lastSolve_t_ = t;
        if (tracking ? !solveTrack(t, filterEstimate, filterSpread_m)
                     : !solve(t, filterEstimate, filterSpread_m))
            solved_.reset(), track_.reset();
    }
    std::optional<TPose2D> smoothed;
    if (tracking)
    {
        if (track_) smoothed = continueTrack(*track_, t);
    }
    else if (const auto* now = odometryAt(t); solved_ && now)
    {
        // The newest solved node continued by the odometry since.
        const auto& [odoNode, poseNode] = *solved_;
        smoothed = (CPose2D(poseNode) + (CPose2D(now->second) - CPose2D(odoNode))).asTPose();
    }
    if (smoothed && !CWiFiBearingMap::inArea(area_, smoothed->x, smoothed->y))
        return std::nullopt;  // the filter's estimate, which the map keeps inside, stands
    return smoothed;
}

double WindowSmoother::recentAoaResidual(
    const Trajectory2D& poses, const std::vector<BearingRecord>& bearings) const
{
    std::vector<double> residuals;
    for (const auto& b : bearings)
    {
        if (!b.hasAoa || b.t < poses.t.back() - kRecent_s) continue;
        const auto* tx = aps_.find(b.transmitter);
        TPose2D robot;
        if (!tx || !poses.interpolate(b.t, robot)) continue;
        const double predicted =
            predictAoa(sensorWorldPose(robot, b.sensorPose), tx->pose.x, tx->pose.y);
        const auto residual = [&](double z, double mirror)
        {
            const double r = std::abs(mrpt::math::wrapToPi(predicted - z));
            return b.aoaAmbiguous ? std::min(r, std::abs(mrpt::math::wrapToPi(predicted - mirror)))
                                  : r;
        };
        double r = residual(b.aoa, b.aoaMirror);
        if (opts_.graph.useAoaAlternatives)
            for (const auto& a : b.aoaAlternatives())
                r = std::min(r, residual(a.aoa, aoaMirrorOf(b, a.aoa)));
        residuals.push_back(r);
    }
    return detail::median(std::move(residuals));  // 0: nothing recent to check against
}

bool WindowSmoother::solve(
    double t, const TPose2D& filterEstimate, const std::function<double()>& filterSpread_m)
{
    const double t0 = t - opts_.window_s;

    GraphSlamInput in;
    for (const auto& [to, p] : odometry_)
        if (to >= t0 && to <= t) in.odometry.push_back(to, p);
    if (in.odometry.size() < 2 || in.odometry.t.back() - in.odometry.t.front() < opts_.minWindow_s)
        return false;
    for (const auto& b : bearings_)
        if (b.t >= in.odometry.t.front() && b.t <= in.odometry.t.back()) in.bearings.push_back(b);
    if (in.bearings.empty()) return false;
    in.aps = aps_;

    // Starts: the odometry frame placed so that its newest reading is at the filter's
    // estimate, and the previous solve continued.
    const CPose2D odoLast(in.odometry.poses.back());
    if (filterSpread_m() <= opts_.maxFilterSpread_m)
        in.placements.push_back((CPose2D(filterEstimate) + (-odoLast)).asTPose());
    if (solved_)
        in.placements.push_back((CPose2D(solved_->second) + (-CPose2D(solved_->first))).asTPose());
    if (in.placements.empty()) return false;

    mrpt::system::CTicTac timer;
    GraphSlamResult r;
    try
    {
        r = solveBearingGraph(in, opts_.graph);
    }
    catch (const std::runtime_error&)
    {
        return false;  // too little in the window: the filter's estimate stands
    }
    ++solves_;
    solveTime_s_ += timer.Tac();
    if (r.poses.empty() || !(r.medianWhitenedResidual <= opts_.maxMedianWhitenedResidual))
        return false;
    // A window that holds a kidnapping is solved across it, the graph bending its odometry
    // over several edges, with the window's residuals hardly grown: the newest bearings, which
    // the newest pose must explain, tell. The graph would bend on for as long as the window
    // holds the jump (the newest residuals shrink while the pose stays off), so the smoother
    // forgets what came before and starts over.
    if (!(recentAoaResidual(r.poses, in.bearings) <= opts_.maxRecentResidual_rad))
    {
        ++restarts_;
        forgetBefore(t);
        return false;
    }
    ++accepted_;
    solved_.emplace(in.odometry.poses.back(), r.poses.poses.back());
    return true;
}

TPose2D WindowSmoother::continueTrack(const Trajectory2D& track, double t)
{
    const size_t n = track.size();
    if (n < 2 || t <= track.t.back()) return track.poses.back();
    // At most 1 s ahead: beyond that the last velocity says little.
    const double f = std::min(t - track.t.back(), 1.0) / (track.t[n - 1] - track.t[n - 2]);
    const TPose2D step = (CPose2D(track.poses[n - 1]) - CPose2D(track.poses[n - 2])).asTPose();
    return (CPose2D(track.poses[n - 1]) + CPose2D(f * step.x, f * step.y, f * step.phi)).asTPose();
}

bool WindowSmoother::solveTrack(
    double t, const TPose2D& filterEstimate, const std::function<double()>& filterSpread_m)
{
    TrackInput in;
    in.t1 = t;
    in.t0 = std::max(t - opts_.trackWindow_s, filterEstimates_.front().first);
    if (!bearings_.empty()) in.t0 = std::max(in.t0, bearings_.front().t);
    if (bearings_.empty() || t - in.t0 < std::max(opts_.minWindow_s, 2 * opts_.track.nodePeriod_s))
        return false;
    for (const auto& b : bearings_)
        if (b.t >= in.t0 && b.t <= t) in.bearings.push_back(b);
    in.aps = aps_;
    in.area = area_;
    in.firstStartMargin = track_ ? opts_.trackSwitchCost : 0.0;

    // Starts: the previous track continued to now at its last velocity, which holds its place
    // unless the filter's recent estimates (while its particles agree) fit clearly better.
    if (track_)
    {
        Trajectory2D continued = *track_;
        if (t > continued.t.back()) continued.push_back(t, continueTrack(*track_, t));
        in.starts.push_back(std::move(continued));
    }
    if (filterSpread_m() <= opts_.maxFilterSpread_m)
    {
        Trajectory2D filterTrack;
        for (const auto& [te, p] : filterEstimates_)
            if (te >= in.t0 - 1) filterTrack.push_back(te, p);
        filterTrack.poses.back() = filterEstimate;
        in.starts.push_back(std::move(filterTrack));
    }
    if (restartPose_ && restartPose_->first < t - opts_.trackWindow_s) restartPose_.reset();
    if (restartPose_)
        for (int k = 0; k < opts_.trackRestartHeadings; ++k)
        {
            TPose2D standing = restartPose_->second;
            standing.phi =
                mrpt::math::wrapToPi(standing.phi + 2 * M_PI * k / opts_.trackRestartHeadings);
            Trajectory2D start;
            start.push_back(in.t0, standing);
            in.starts.push_back(std::move(start));
        }
    if (in.starts.empty()) return false;
    mrpt::system::CTicTac timer;
    TrackResult r;
    try
    {
        r = solveBearingTrack(in, opts_.track, opts_.graph);
    }
    catch (const std::runtime_error&)
    {
        return false;  // too little in the window: the filter's estimate stands
    }
    ++solves_;
    solveTime_s_ += timer.Tac();
    if (!(r.medianWhitenedResidual <= opts_.maxMedianWhitenedResidual)) return false;
    // As with odometry: the newest pose must explain the newest bearings, else start over.
    if (!(recentAoaResidual(r.poses, in.bearings) <= opts_.maxRecentResidual_rad))
    {
        ++restarts_;
        forgetBefore(t);
        if (track_ && opts_.trackRestartHeadings > 0)
            restartPose_.emplace(track_->t.back(), track_->poses.back());
        return false;
    }
    ++accepted_;
    track_ = std::move(r.poses);
    restartPose_.reset();
    return true;
}

}  // namespace mrpt_wifi::localization
