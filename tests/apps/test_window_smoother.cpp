/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/math/TBoundingBox.h>
#include <mrpt/math/wrap2pi.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt_wifi/localization/WindowSmoother.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "SyntheticWorld.h"
#include "TrackFromTruth.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;
using namespace mrpt_wifi::loctest;

namespace
{
TransmitterMap roomAps()
{
    return makeAps({{0.3, 7.7, -0.785}, {9.7, 7.7, -2.36}, {9.7, 0.3, 2.36}, {0.3, 0.3, 0.785}});
}

/** Drifting odometry (3 % scale, 0.5 deg/m) and AoA with a multipath field of 2 deg: what
 *  makes a pose-only particle filter lag. */
World driftingDrive()
{
    WorldOptions o;
    o.duration_s = 60;
    o.loop = {{2, 2}, {8, 2}, {8, 6}, {2, 6}};
    o.odoScaleError = 0.03;
    o.odoYawDrift = 0.5 * M_PI / 180;
    o.aod = false;
    o.multipathAmplitude = 2 * M_PI / 180;
    o.rate_Hz = 10;
    return makeWorld(roomAps(), o);
}

struct Replay
{
    std::vector<double> filterErrors, smoothedErrors;
    std::vector<double> lateSmoothedErrors;  //!< of the last 8 s
    std::vector<double> times;               //!< of smoothedErrors
    size_t estimates = 0;
};

/** Feeds the smoother the drive in time order, with odometry `odometry` and, as the particle
 *  filter's estimate at each bearing, `filterAt(t)`. */
template <class FilterAt>
Replay replay(
    const World& w, const Trajectory2D& odometry, WindowSmoother& smoother, FilterAt filterAt)
{
    Replay r;
    size_t io = 0;
    for (const auto& b : w.bearings)
    {
        for (; io < odometry.size() && odometry.t[io] <= b.t; ++io)
            smoother.addOdometry(odometry.t[io], odometry.poses[io]);
        smoother.addBearing(b);
        mrpt::math::TPose2D truth;
        if (!w.truth.interpolate(b.t, truth)) continue;
        const auto filter = filterAt(b.t, truth);
        ++r.estimates;
        const auto s = smoother.update(b.t, filter, [] { return 0.3; });
        if (!s) continue;
        r.filterErrors.push_back(std::hypot(filter.x - truth.x, filter.y - truth.y));
        r.smoothedErrors.push_back(std::hypot(s->x - truth.x, s->y - truth.y));
        r.times.push_back(b.t);
        if (b.t > w.bearings.back().t - 8) r.lateSmoothedErrors.push_back(r.smoothedErrors.back());
    }
    return r;
}

/** A skewed loop in roomAps()'s room, AoA only at 10 bearings/s per AP. */
WorldOptions loopWithoutAod(double duration_s)
{
    WorldOptions o;
    o.duration_s = duration_s;
    o.loop = {{2, 2}, {8, 2.5}, {7, 6}, {2, 5.5}};
    o.aod = false;
    o.rate_Hz = 10;
    return o;
}

/** The track of the 20 s up to 30 s into `w`, started from a filter 0.5 m behind the robot
 *  and 10° off its heading. */
TrackInput laggingStartInput(const World& w)
{
    TrackInput in;
    in.t1 = w.truth.t.front() + 30, in.t0 = in.t1 - 20;
    in.aps = w.aps, in.bearings = w.bearings;
    const mrpt::poses::CPose2D lag(-0.5, 0.2, 10 * M_PI / 180);
    Trajectory2D start;
    for (size_t i = 0; i < w.truth.size(); i += 10)
        start.push_back(w.truth.t[i], (mrpt::poses::CPose2D(w.truth.poses[i]) + lag).asTPose());
    in.starts = {start};
    return in;
}

double median(std::vector<double> v)
{
    std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
    return v[v.size() / 2];
}
}  // namespace

TEST(WindowSmoother, RefinesAFilterThatLagsBehindDriftingOdometry)
{
    const auto w = driftingDrive();
    WindowSmoother smoother(WindowSmootherOptions(), w.aps);
    // A filter that lags 0.5 m behind the robot and 5 deg off its heading.
    const mrpt::poses::CPose2D lag(-0.5, 0.1, 5 * M_PI / 180);
    const auto r = replay(
        w, w.odometry, smoother,
        [&](double, const mrpt::math::TPose2D& truth)
        { return (mrpt::poses::CPose2D(truth) + lag).asTPose(); });
    // Refined from min_window_s (5 s) on: most of the 60 s drive.
    EXPECT_GT(r.smoothedErrors.size(), r.estimates * 8 / 10);
    EXPECT_GT(smoother.accepted(), 100u);
    EXPECT_LT(median(r.smoothedErrors), 0.15);
    EXPECT_LT(median(r.smoothedErrors), 0.3 * median(r.filterErrors));
}

TEST(WindowSmoother, NeverHoldsOnToAPoseFromBeforeAKidnapping)
{
    const auto w = driftingDrive();
    // At 30 s the robot is carried off: its odometry's relation to the map jumps by 2 m and
    // 30 deg (the same to the smoother as the robot jumping while the odometry does not).
    const double tKidnap = w.odometry.t.front() + 30;
    const mrpt::poses::CPose2D jump(2.0, -1.0, 30 * M_PI / 180);
    Trajectory2D odometry;
    for (size_t i = 0; i < w.odometry.size(); ++i)
        odometry.push_back(
            w.odometry.t[i], w.odometry.t[i] < tKidnap
                                 ? w.odometry.poses[i]
                                 : (jump + mrpt::poses::CPose2D(w.odometry.poses[i])).asTPose());
    WindowSmoother smoother(WindowSmootherOptions(), w.aps);
    // The filter recovers at once: its estimate is the truth.
    const auto r = replay(
        w, odometry, smoother, [](double, const mrpt::math::TPose2D& truth) { return truth; });
    ASSERT_FALSE(r.smoothedErrors.empty());
    // The first solve whose newest bearings the newest pose cannot explain makes the smoother
    // start over: within a second (two solves) it no longer carries the old place on, where
    // the graph left alone bends across the jump and stays 1.1 m off for 10 s.
    EXPECT_GE(smoother.restarts(), 1u);
    for (size_t i = 0; i < r.times.size(); ++i)
    {
        if (r.times[i] > tKidnap + 1.5)
        {
            EXPECT_LT(r.smoothedErrors[i], 0.3) << "at " << r.times[i] - tKidnap << " s";
        }
    }
    // Once the window has passed the jump, it refines as before.
    EXPECT_LT(median(r.lateSmoothedErrors), 0.15);
}

TEST(WindowSmoother, NothingBeforeMinWindowAndWhenDisabled)
{
    const auto w = driftingDrive();
    WindowSmootherOptions o;
    o.minWindow_s = 10;
    WindowSmoother early(o, w.aps);
    const double t0 = w.odometry.t.front();
    const auto r = replay(
        w, w.odometry, early,
        [&](double t, const mrpt::math::TPose2D& truth)
        {
            if (t < t0 + 9.5)
            {
                EXPECT_EQ(early.accepted(), 0u);
            }
            return truth;
        });
    EXPECT_GT(early.accepted(), 0u);
    // Bearings alone, update() never called (e.g. a live chain before its filter steps): the
    // bearings kept stay within the window, however long the robot drives.
    WindowSmoother noOdometry(WindowSmootherOptions(), w.aps);
    size_t perSecond = 0;
    for (const auto& b : w.bearings)
    {
        noOdometry.addBearing(b);
        perSecond += b.t < t0 + 1;
    }
    EXPECT_LE(
        noOdometry.bufferedBearings(), size_t(perSecond * (noOdometry.options().window_s + 2)));
    EXPECT_GT(noOdometry.bufferedBearings(), 0u);
    o.enabled = false;
    WindowSmoother off(o, w.aps);
    EXPECT_TRUE(
        replay(w, w.odometry, off, [](double, const auto& p) { return p; }).smoothedErrors.empty());
    EXPECT_EQ(off.solves(), 0u);
    EXPECT_EQ(off.bufferedBearings(), 0u);
}

TEST(WindowSmoother, ConfigErrorsNameTheKey)
{
    for (const std::string bad :
         {"window_s = 0", "min_window_s = 30", "solve_period_s = -1", "loss = tukey",
          "max_median_whitened_residual = 0", "track_window_s = 1", "track_node_period_s = 0",
          "track_accel_std = -1", "track_turn_accel_std_deg = 0", "track_lateral_std_m = 0",
          "track_switch_cost = -1", "track_restart_headings = -1"})
    {
        mrpt::config::CConfigFileMemory ini("[WindowSmoother]\n" + bad + "\n");
        WindowSmootherOptions o;
        try
        {
            o.loadFromConfigFile(ini, "WindowSmoother");
            ADD_FAILURE() << bad << " accepted";
        }
        catch (const std::invalid_argument& e)
        {
            const std::string key = bad.substr(0, bad.find(' '));
            EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
        }
    }
    mrpt::config::CConfigFileMemory ini("[WindowSmoother]\nenabled = false\nwindow_s = 12\n");
    WindowSmootherOptions o;
    o.loadFromConfigFile(ini, "WindowSmoother");
    EXPECT_FALSE(o.enabled);
    EXPECT_DOUBLE_EQ(o.window_s, 12);
    EXPECT_EQ(o.asString(), "off");
}

namespace
{
/** The drive of driftingDrive() without its odometry: multipath of 2 deg, AoA at 10 Hz per AP. */
double nodeError(const Trajectory2D& track, const Trajectory2D& truth, size_t k)
{
    mrpt::math::TPose2D p;
    if (!truth.interpolate(track.t[k], p)) return INFINITY;
    return std::hypot(track.poses[k].x - p.x, track.poses[k].y - p.y);
}
}  // namespace

TEST(BearingTrack, FollowsARobotWithoutOdometryFromALaggingStart)
{
    const auto w = driftingDrive();
    auto in = laggingStartInput(w);
    const double t1 = in.t1;
    const Trajectory2D start = in.starts.front();
    TrackMotionPrior prior;
    prior.forwardOnly = true;
    GraphSlamOptions g = WindowSmootherOptions::defaultGraph();
    g.useAod = false;
    const auto r = solveBearingTrack(in, prior, g);
    ASSERT_EQ(r.poses.size(), 41u);  // every 0.5 s over 20 s, both ends
    EXPECT_DOUBLE_EQ(r.poses.t.back(), t1);
    std::vector<double> errors, headingErrors;
    for (size_t k = 0; k < r.poses.size(); ++k)
    {
        errors.push_back(nodeError(r.poses, w.truth, k));
        mrpt::math::TPose2D p;
        w.truth.interpolate(r.poses.t[k], p);
        headingErrors.push_back(std::abs(mrpt::math::wrapToPi(r.poses.poses[k].phi - p.phi)));
    }
    // Bearings alone place the track (the start was 0.5 m off), and moving along its heading
    // gives the heading (the corners, where the loop turns on the spot, excepted).
    EXPECT_LT(median(errors), 0.15);
    // The newest node, the estimate, has only the bearings of the last step on one side: it is
    // the least certain (0.33 m here), still closer than the start (0.54 m).
    EXPECT_LT(errors.back(), 0.4);
    EXPECT_LT(median(headingErrors), 5 * M_PI / 180);
    EXPECT_LT(r.medianWhitenedResidual, 1.0);
    EXPECT_EQ(r.start, 0u);

    // A second start far off that fits worse loses; by less than the margin it would not
    // replace the first start, and an area holds the nodes inside it.
    Trajectory2D far;
    for (size_t i = 0; i < start.size(); ++i)
        far.push_back(start.t[i], mrpt::math::TPose2D(1, 1, 0));
    in.starts = {far, start};
    in.firstStartMargin = 0;
    EXPECT_EQ(solveBearingTrack(in, prior, g).start, 1u);
    in.area = mrpt::math::TBoundingBox({0, 0, 0}, {10, 3, 0});  // the loop reaches y = 6
    const auto bounded = solveBearingTrack(in, prior, g);
    for (const auto& p : bounded.poses.poses) EXPECT_LT(p.y, 3.2);
}

TEST(BearingTrack, WeighsBothDirectionsOfAWindowThatCannotTell)
{
    // Three of the four APs only give windows that can't tell their direction from another one
    // 90° away, mirrors included (as near endfire): σ 70° reaches both, each direction alone
    // has its own σ.
    auto w = driftingDrive();
    for (auto& b : w.bearings)
        if (b.transmitter != w.aps.at(3).mac)
        {
            b.hasAoaAlternative = true;
            b.aoaAlternative = b.aoa - std::copysign(M_PI / 2, b.aoa);
            b.aoaAlternativeWeight = 0.5;  // as likely as the reported one
            b.aoaDirectionStd = b.aoaStd;
            b.aoaStd = 70 * M_PI / 180;
        }
    const auto in = laggingStartInput(w);
    TrackMotionPrior prior;
    prior.forwardOnly = true;
    GraphSlamOptions g = WindowSmootherOptions::defaultGraph();
    g.useAod = false;
    const auto medianError = [&](const TrackResult& r)
    {
        std::vector<double> errors;
        for (size_t k = 0; k < r.poses.size(); ++k)
            errors.push_back(nodeError(r.poses, w.truth, k));
        return median(errors);
    };
    g.useAoaAlternatives = false;  // one direction with the σ that reaches both
    const double wide = medianError(solveBearingTrack(in, prior, g));
    g.useAoaAlternatives = true;
    const double both = medianError(solveBearingTrack(in, prior, g));
    // Four sure APs: 0.09 m; one AP alone: 7 m.
    EXPECT_LT(both, 0.12) << "as with four sure APs";
    EXPECT_GT(wide, 1.5 * both) << "one AP's bearings and three 70° ones: wide " << wide;
}

TEST(BearingTrack, WeighedAlternativesKeepTheTruthAgainstReflections)
{
    // Issue 53 (room 2): three of the four APs' strongest paths are reflections that fit a
    // track 1.5 m off the truth. Each bearing carries two alternatives: a second reflection
    // that fits nothing (weight 0.4) and the direct path (0.35); the reported one keeps
    // 0.25. The graph's weighted max-mixture of all of them keeps the true track; one
    // direction per bearing, or the first alternative only, follows the reflections.
    auto w = driftingDrive();
    const mrpt::math::TPoint2D shift(-0.9, 1.2);
    for (auto& b : w.bearings)
    {
        const auto* ap = w.aps.find(b.transmitter);
        mrpt::math::TPose2D truth;
        if (b.transmitter == w.aps.at(3).mac || !ap || !w.truth.interpolate(b.t, truth)) continue;
        const mrpt::math::TPose2D off(truth.x + shift.x, truth.y + shift.y, truth.phi);
        b.hasAoaAlternative = true;
        b.aoaAlternative = wrapToPi(b.aoa + 70 * M_PI / 180);
        b.aoaAlternativeWeight = 0.4;
        b.moreAoaAlternatives = {{b.aoa, 0.35}};
        b.aoaDirectionStd = b.aoaStd;
        b.aoa = predictAoa(sensorWorldPose(off, b.sensorPose), ap->pose.x, ap->pose.y);
        b.aoaMirror = w.rxArray.mirrorOf(b.aoa);  // the pair stays across the array's axis
    }
    const auto in = laggingStartInput(w);
    TrackMotionPrior prior;
    prior.forwardOnly = true;
    GraphSlamOptions g = WindowSmootherOptions::defaultGraph();
    g.useAod = false;
    const auto medianError = [&](const TrackInput& input)
    {
        const auto r = solveBearingTrack(input, prior, g);
        std::vector<double> errors;
        for (size_t k = 0; k < r.poses.size(); ++k)
            errors.push_back(nodeError(r.poses, w.truth, k));
        return median(errors);
    };
    g.useAoaAlternatives = false;
    const double single = medianError(in);
    g.useAoaAlternatives = true;
    const double mixture = medianError(in);
    auto firstOnly = in;
    for (auto& b : firstOnly.bearings) b.moreAoaAlternatives.clear();
    const double first = medianError(firstOnly);
    EXPECT_LT(mixture, 0.15) << "the mixture keeps the truth (one direction: " << single
                             << " m, first alternative only: " << first << " m)";
    EXPECT_GT(single, 0.5) << "one direction per bearing follows the reflections";
    EXPECT_GT(first, 0.5) << "without the direct path the reflections win";
}

TEST(BearingTrack, RefusesWhatItCannotSolve)
{
    const auto w = driftingDrive();
    TrackInput in;
    in.aps = w.aps, in.bearings = w.bearings;
    in.t0 = w.truth.t.front() + 10, in.t1 = in.t0 + 10;
    GraphSlamOptions g;
    EXPECT_THROW(solveBearingTrack(in, TrackMotionPrior(), g), std::runtime_error);  // no start
    in.starts = {w.truth};
    in.t1 = in.t0 + 0.1;  // shorter than a node step
    EXPECT_THROW(solveBearingTrack(in, TrackMotionPrior(), g), std::runtime_error);
    in.t1 = in.t0 + 10;
    in.aps = TransmitterMap();  // none of the bearings' transmitters
    EXPECT_THROW(solveBearingTrack(in, TrackMotionPrior(), g), std::runtime_error);
}

TEST(WindowSmoother, WithoutOdometryFitsATrackToTheBearings)
{
    const auto w = driftingDrive();
    const Trajectory2D none;
    // A filter without odometry: 0.4 m behind the robot and 8 deg off.
    const mrpt::poses::CPose2D lag(-0.4, 0.15, 8 * M_PI / 180);
    const auto filterAt = [&](double, const mrpt::math::TPose2D& truth)
    { return (mrpt::poses::CPose2D(truth) + lag).asTPose(); };
    WindowSmoother smoother(WindowSmootherOptions(), w.aps);
    const auto r = replay(w, none, smoother, filterAt);
    EXPECT_GT(r.smoothedErrors.size(), r.estimates * 8 / 10);
    EXPECT_GT(smoother.accepted(), 80u);
    EXPECT_LT(median(r.smoothedErrors), 0.2);
    EXPECT_LT(median(r.smoothedErrors), 0.5 * median(r.filterErrors));

    // Switched off: the filter's estimate stands.
    WindowSmootherOptions off;
    off.withoutOdometry = false;
    WindowSmoother filterOnly(off, w.aps);
    EXPECT_TRUE(replay(w, none, filterOnly, filterAt).smoothedErrors.empty());

    // An area that leaves out part of the drive: no smoothed estimate lies outside it.
    WindowSmoother bounded(WindowSmootherOptions(), w.aps);
    bounded.setArea(mrpt::math::TBoundingBox({0, 0, 0}, {10, 4, 0}));
    size_t outside = 0, inside = 0;
    for (const auto& b : w.bearings)
    {
        bounded.addBearing(b);
        mrpt::math::TPose2D truth;
        if (!w.truth.interpolate(b.t, truth)) continue;
        if (const auto s = bounded.update(b.t, filterAt(b.t, truth), [] { return 0.3; }))
            (s->y > 4 ? outside : inside)++;
    }
    EXPECT_EQ(outside, 0u);
    EXPECT_GT(inside, 0u);
}

TEST(WindowSmoother, WithoutOdometryResumesWhereTheRobotStoppedToTurn)
{
    // The robot stands at each corner and turns on the spot (by 80-101 deg) for about 2 s, its
    // bearings wide meanwhile; the filter, its constant-velocity guess driving on, is lost from
    // the first corner on (it carries straight on along the first side).
    WorldOptions o = loopWithoutAod(60);
    o.cornerTurnRate = M_PI / 4;
    const auto w = makeWorld(roomAps(), o);
    const auto &start = o.loop[0], &corner = o.loop[1];
    const double dx = corner.x - start.x, dy = corner.y - start.y, side = std::hypot(dx, dy);
    const double firstCorner = w.truth.t.front() + side / o.speed;
    const auto lostFilter = [&](double t, const mrpt::math::TPose2D& truth)
    {
        if (t < firstCorner) return truth;
        const double d = side + o.speed * (t - firstCorner);
        return mrpt::math::TPose2D(
            start.x + d * dx / side, start.y + d * dy / side, std::atan2(dy, dx));
    };
    // Median error of the smoothed estimates from 10 s after the first corner on, and their
    // count.
    const auto lateError = [&](int restartHeadings, size_t& late)
    {
        WindowSmootherOptions opts;
        opts.trackRestartHeadings = restartHeadings;
        WindowSmoother smoother(opts, w.aps);
        const auto r = replay(w, Trajectory2D(), smoother, lostFilter);
        std::vector<double> errors;
        for (size_t i = 0; i < r.times.size(); ++i)
            if (r.times[i] > firstCorner + 10) errors.push_back(r.smoothedErrors[i]);
        late = errors.size();
        return errors.empty() ? HUGE_VAL : median(errors);
    };
    size_t refined = 0, refinedFromFilter = 0;
    const double shipped = lateError(WindowSmootherOptions().trackRestartHeadings, refined);
    const double fromFilterOnly = lateError(0, refinedFromFilter);
    std::cout << "from 10 s after the first corner: median error " << shipped << " m over "
              << refined << " estimates; from the filter only: " << fromFilterOnly << " m over "
              << refinedFromFilter << "\n";
    EXPECT_LT(shipped, 0.3);
    EXPECT_GT(refined, 500u);        // of about 1500 bearings from then on
    EXPECT_GT(fromFilterOnly, 1.0);  // what the restart pose is for
}

TEST(TrackFromTruth, SaysWhereTheBearingsAloneLeaveThePoseOpen)
{
    // The evaluator's best case of the no-odometry track (localization-accuracy
    // --track-from-truth): with four APs in the corners the bearings pin the robot down; with
    // the four APs 0.4 m apart in one corner they give one direction and the robot's heading is
    // unknown, so its range along that direction is open (the information limit, not search).
    const WorldOptions o = loopWithoutAod(40);
    WindowSmootherOptions options;
    options.track.forwardOnly = true;
    options.graph.useAod = false;
    const mrpt::math::TBoundingBox area({0, 0, 0}, {10, 8, 0});

    const auto corners = makeWorld(roomAps(), o);
    const auto spread = trackFromTruth(corners.bearings, corners.aps, corners.truth, options, area);
    EXPECT_GE(spread.newestErrors_m.size(), 35u);  // every second from 5 s on
    EXPECT_LT(spread.median_m, 0.15);

    const auto clustered = makeWorld(
        makeAps({{0.3, 0.3, 0.785}, {0.7, 0.3, 0.785}, {0.3, 0.7, 0.785}, {0.7, 0.7, 0.785}}), o);
    const auto open =
        trackFromTruth(clustered.bearings, clustered.aps, clustered.truth, options, area);
    EXPECT_GT(open.median_m, 0.5);
    EXPECT_GT(open.median_m, 4 * spread.median_m);
    std::cout << "track from the true poses: " << spread.median_m << " m (APs in the corners), "
              << open.median_m << " m (APs in one corner)\n";
}
