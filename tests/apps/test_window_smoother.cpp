/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt_wifi/localization/WindowSmoother.h>

#include <algorithm>

#include "SyntheticWorld.h"

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
    // Without odometry (live, before the first reading) update() is never called: the
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
          "max_median_whitened_residual = 0"})
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
