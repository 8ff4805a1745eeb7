/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

// The best case of the no-odometry track fit in a recorded drive: the window smoother's track
// (solveBearingTrack) started from the true poses instead of the filter's estimates. Where
// even that is off, the bearings do not pin the robot down without odometry (geometry,
// multipath): a better search cannot help, only more information can. Where it is close while
// the filter is off, the filter settled on another place that fits (ambiguity, search).

#include <mrpt/math/TBoundingBox.h>
#include <mrpt_wifi/localization/BearingTrack.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/localization/WindowSmoother.h>

#include <algorithm>  // std::max
#include <cmath>
#include <optional>
#include <stdexcept>
#include <vector>

namespace mrpt_wifi::loctest
{
struct TrackFromTruth
{
    std::vector<double> newestErrors_m;  //!< error of each solve's newest node (the estimate)
    double median_m = NAN;               //!< NaN when no window could be solved
    /** The median over the windows a full track_window_s long only (the smoother's steady
     *  state, as after a filter converged; the first windows hold less): NaN when none. */
    double fullWindowMedian_m = NAN;
};

/** Every `step_s` from `options.minWindow_s` after the first true pose on, the track of the
 *  last `options.trackWindow_s` is fitted (the shipped motion prior and bearing options, the
 *  room's `area`) from the true poses of that window; the error of its newest node against the
 *  truth, the pose the smoother would report. `options.track.forwardOnly` and the graph's
 *  useAoa / useAod must be set as the apps set them. */
inline TrackFromTruth trackFromTruth(
    const std::vector<localization::BearingRecord>& bearings,
    const localization::TransmitterMap& aps, const localization::Trajectory2D& truth,
    const localization::WindowSmootherOptions& options,
    const std::optional<mrpt::math::TBoundingBox>& area, double step_s = 1.0)
{
    using namespace localization;
    TrackFromTruth out;
    if (truth.size() < 2) return out;
    std::vector<double> fullWindowErrors_m;
    for (double t1 = truth.t.front() + options.minWindow_s; t1 <= truth.t.back(); t1 += step_s)
    {
        TrackInput in;
        in.t1 = t1;
        in.t0 = std::max(truth.t.front(), t1 - options.trackWindow_s);
        for (const auto& b : bearings)
            if (b.t >= in.t0 && b.t <= t1) in.bearings.push_back(b);
        in.aps = aps;
        in.area = area;
        Trajectory2D start;
        for (size_t i = 0; i < truth.size(); ++i)
            if (truth.t[i] >= in.t0 - 0.5 && truth.t[i] <= t1 + 0.5)
                start.push_back(truth.t[i], truth.poses[i]);
        in.starts = {start};
        TrackResult r;
        try
        {
            r = solveBearingTrack(in, options.track, options.graph);
        }
        catch (const std::runtime_error&)
        {
            continue;  // too little in this window
        }
        mrpt::math::TPose2D g;
        if (!truth.interpolate(r.poses.t.back(), g)) continue;
        const auto& p = r.poses.poses.back();
        out.newestErrors_m.push_back(std::hypot(p.x - g.x, p.y - g.y));
        if (t1 - truth.t.front() >= options.trackWindow_s)
            fullWindowErrors_m.push_back(out.newestErrors_m.back());
    }
    if (!out.newestErrors_m.empty()) out.median_m = computeStats(out.newestErrors_m).median;
    if (!fullWindowErrors_m.empty())
        out.fullWindowMedian_m = computeStats(fullWindowErrors_m).median;
    return out;
}

}  // namespace mrpt_wifi::loctest
