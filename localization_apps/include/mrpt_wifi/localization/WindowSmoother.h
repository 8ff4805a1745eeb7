/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/math/TPose2D.h>
#include <mrpt_wifi/localization/BearingGraphSlam.h>
#include <mrpt_wifi/localization/BearingRecord.h>
#include <mrpt_wifi/localization/BearingTrack.h>
#include <mrpt_wifi/localization/TransmitterMap.h>

#include <cmath>
#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace mrpt_wifi::localization
{
/** Options of WindowSmoother: section `[WindowSmoother]` of the localization .ini. */
struct WindowSmootherOptions
{
    bool enabled = true;         //!< `enabled`
    double window_s = 20;        //!< `window_s`: odometry and bearings of the last this many s
    double minWindow_s = 5;      //!< `min_window_s`: no solve on less data than this
    double solvePeriod_s = 0.5;  //!< `solve_period_s`: a solve every this much time
    /** `max_median_whitened_residual`: a solve is used only if its bearings' median
     *  |residual|/σ is at most this (a start in the wrong mode leaves large residuals). */
    double maxMedianWhitenedResidual = 1.0;
    /** `max_filter_spread_m`: a first solve (or one after a rejected solve) starts from the
     *  particle filter's estimate only when the particles' spread is at most this. */
    double maxFilterSpread_m = 1.0;
    /** `max_recent_residual_deg`: when the median |AoA residual| of the bearings of a solve's
     *  last 2 s exceeds this, the solve is not used and the smoother starts over from then
     *  (forgets the older odometry and bearings): the newest pose must explain the newest
     *  bearings. A kidnapping inside the window is solved across it, the graph bending the
     *  odometry over several edges with the window's residuals hardly grown and, later, the
     *  newest residuals shrinking while the pose stays off. */
    double maxRecentResidual_rad = 8 * M_PI / 180;
    /** The window's graph: odometry edges, systematic odometry errors and bearing edges as
     *  wifi-graphslam --aps builds them (its defaults; node_period_s, odometry_scale_std,
     *  odometry_yaw_drift_deg_per_m, min_std_deg, loss, bearing_decorrelation_m,
     *  max_iterations). Which angles it uses (useAoa, useAod) the apps set from the map's
     *  likelihood options, so the smoother trusts what the filter trusts. */
    GraphSlamOptions graph = defaultGraph();
    /** `without_odometry`: while no odometry has arrived, each solve fits a track to the
     *  bearings of the last `track_window_s` with `track` as the motion prior
     *  (solveBearingTrack), started from the filter's recent estimates and from the previous
     *  solve continued; the same tests decide whether it is used. false: nothing without
     *  odometry (the filter's estimate stands). */
    bool withoutOdometry = true;
    double trackWindow_s = 20;  //!< `track_window_s`
    /** `track_switch_cost`: the previous track continued stays the estimate unless the
     *  filter's start ends with a cost lower by more than this (TrackInput::firstStartMargin). */
    double trackSwitchCost = 3;
    /** `track_restart_headings`: when a track's newest pose stops explaining the newest
     *  bearings (a restart), its last accepted pose is offered as a start of the next tracks,
     *  standing, at this many headings spread over the circle, beside the filter's estimates,
     *  until a track is accepted again or it is older than track_window_s. Why: a robot that
     *  stops and turns on the spot gives wide bearings while its track drives on at its last
     *  speed; the filter, whose constant-velocity guess drove on too, is no better start, while
     *  the place where the track was last right is where the robot turned. 0: the filter's
     *  estimates only. */
    int trackRestartHeadings = 4;
    TrackMotionPrior track;  //!< `track_*` keys (TrackMotionPrior::loadFromConfigFile)

    static GraphSlamOptions defaultGraph();
    void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& section);
    std::string asString() const;
};

/** Fixed-lag smoothing of a particle filter's estimate with odometry and known transmitters:
 *  every solve_period_s the odometry and bearings of the last window_s seconds form a pose
 *  graph (solveBearingGraph with the known APs fixed, systematic odometry scale and heading
 *  drift estimated), started from the filter's estimate and from the previous solve
 *  continued by the odometry; the lower final cost wins, and the newest node's pose, continued
 *  by the odometry, is the estimate. Causal: the estimate at t uses data up to t only.
 *
 *  Why: the filter holds pose only, so a systematic odometry error (a scale error, a heading
 *  drift per metre) shows as a lag it keeps correcting, and the bearings of one step are its
 *  only evidence; the window sees the odometry's shape over many metres and the bearings of
 *  many places at once (development rooms 1-10: the whole drive's graph was 0.04-0.18 m off
 *  where the filter was 0.3-0.7 m off).
 *
 *  The particle filter stays in charge of where the robot is (kidnapping, recovery): the
 *  smoother only refines it, and a solve that does not fit the bearings, or whose newest pose
 *  does not explain the newest bearings (a kidnapping inside the window: then it starts
 *  over), gives nothing.
 *
 *  Without odometry (none added, options.withoutOdometry) the window is a track fitted to the
 *  bearings with a motion prior instead (solveBearingTrack), started from the filter's
 *  estimates given to update() and from the previous track continued at its last velocity
 *  (after a restart also from the last accepted pose, standing: trackRestartHeadings);
 *  between solves the newest node continued at that velocity is the estimate. Not
 *  thread-safe. */
class WindowSmoother
{
public:
    WindowSmoother(const WindowSmootherOptions& options, const TransmitterMap& aps);

    const WindowSmootherOptions& options() const { return opts_; }
    /** The area the robot can be in (the map's): a smoothed pose outside it is not used, and a
     *  track is held inside it. */
    void setArea(const std::optional<mrpt::math::TBoundingBox>& area) { area_ = area; }

    /** Odometry readings in time order (older or equal times are dropped). Both add* keep only
     *  the last window_s (+ 1 s) of data; nothing while disabled. */
    void addOdometry(double t, const mrpt::math::TPose2D& odometry);
    /** Bearings of transmitters not in the map are ignored. */
    void addBearing(const BearingRecord& b);

    /** The smoothed pose at `t` (solving if solve_period_s has passed since the last solve),
     *  given the filter's estimate at `t` and its spread [m], asked for only when a solve is
     *  due (a pass over the particles); nullopt while there is no accepted solve (then the
     *  filter's estimate stands). */
    std::optional<mrpt::math::TPose2D> update(
        double t, const mrpt::math::TPose2D& filterEstimate,
        const std::function<double()>& filterSpread_m);

    size_t solves() const { return solves_; }
    /** Bearings kept for the next window. */
    size_t bufferedBearings() const { return bearings_.size(); }
    size_t accepted() const { return accepted_; }
    /** Solves whose newest bearings the newest pose did not explain (max_recent_residual_deg). */
    size_t restarts() const { return restarts_; }
    double solveTime_s() const { return solveTime_s_; }

private:
    bool solve(
        double t, const mrpt::math::TPose2D& filterEstimate,
        const std::function<double()>& filterSpread_m);
    /** Median |AoA residual| [rad] of the bearings of the last kRecent_s of `poses`; 0 if none. */
    double recentAoaResidual(
        const Trajectory2D& poses, const std::vector<BearingRecord>& bearings) const;
    static constexpr double kRecent_s = 2.0;
    /** Without odometry: solveBearingTrack on the last track_window_s. */
    bool solveTrack(
        double t, const mrpt::math::TPose2D& filterEstimate,
        const std::function<double()>& filterSpread_m);
    /** The newest node of `track` continued to `t` at the velocity of its last step. */
    static mrpt::math::TPose2D continueTrack(const Trajectory2D& track, double t);
    /** Drops the bearings and filter estimates before t and the odometry readings before the
     *  last one at or before t. */
    void forgetBefore(double t);
    /** The newest odometry reading at or before t. */
    const std::pair<double, mrpt::math::TPose2D>* odometryAt(double t) const;

    WindowSmootherOptions opts_;
    TransmitterMap aps_;
    std::optional<mrpt::math::TBoundingBox> area_;
    std::deque<std::pair<double, mrpt::math::TPose2D>> odometry_;
    std::deque<BearingRecord> bearings_;
    /** The last accepted solve: the newest node's odometry reading and its solved pose. */
    std::optional<std::pair<mrpt::math::TPose2D, mrpt::math::TPose2D>> solved_;
    /** Without odometry: the filter's estimates given to update(), and the last accepted
     *  track. */
    std::deque<std::pair<double, mrpt::math::TPose2D>> filterEstimates_;
    std::optional<Trajectory2D> track_;
    /** Without odometry: the newest pose of the last accepted track before a restart. */
    std::optional<std::pair<double, mrpt::math::TPose2D>> restartPose_;
    double lastSolve_t_ = -1e300;
    size_t solves_ = 0, accepted_ = 0, restarts_ = 0;
    double solveTime_s_ = 0;
};

}  // namespace mrpt_wifi::localization
