/* BearingTracker on hand-made candidates: an endfire alias is replaced by the direction the
 * track predicts, a clean central bearing is never overruled, a lost track starts over, a track
 * at the wrong endfire does not keep itself alive. */
#include <gtest/gtest.h>
#include <mrpt_wifi/obs/bearing/BearingTracker.h>

#include "SyntheticCsi.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::bearing;

namespace
{
constexpr double kDeg = M_PI / 180;
const MacAddress kAp = MacAddress::fromString("02:00:00:00:0a:01");

/** Angle `offBroadside` [deg] from the array's broadside, in its front half-plane. */
double at(const AntennaArray& rx, double offBroadside)
{
    return wrapAngle(rx.broadside() + offBroadside * kDeg);
}
}  // namespace

TEST(BearingTracker, ReplacesTheOtherEndfireByTheTrackedOne)
{
    const AntennaArray rx = test::loadArray("rt-ac86u");
    BearingTracker tracker;
    // The robot turns 3° per window: the transmitter moves from 50° towards endfire.
    double yaw = 0;
    for (int n = 0; n < 10; ++n, yaw -= 3 * kDeg)
    {
        const auto d = tracker.update(
            kAp, 0.1 * n, mrpt::math::TPose2D(0, 0, yaw), rx, {{at(rx, 50 + 3 * n), 1.0}},
            2 * kDeg);
        EXPECT_EQ(d.chosen, 0u);
    }
    // Now at 80°: the window's strongest direction is the other endfire (−86°), the true one
    // is its second candidate, and the window says it can't tell (the estimator's σ covers
    // the other endfire). The track takes the true one.
    const auto d = tracker.update(
        kAp, 1.0, mrpt::math::TPose2D(0, 0, yaw), rx, {{at(rx, -86), 1.0}, {at(rx, 81), 0.8}},
        60 * kDeg);
    EXPECT_EQ(d.chosen, 1u);
    EXPECT_TRUE(d.confident);
    EXPECT_LT(d.disagreement_rad, 5 * kDeg);
}

TEST(BearingTracker, NeverOverrulesACentralBearing)
{
    const AntennaArray rx = test::loadArray("rt-ac86u");
    BearingTracker tracker;
    for (int n = 0; n < 10; ++n)
        tracker.update(
            kAp, 0.1 * n, mrpt::math::TPose2D(0, 0, 0), rx, {{at(rx, -40), 1.0}}, 2 * kDeg);
    // The path jumps to 10° (a reflection took over the track before, or the direct path
    // reappeared): the central bearing stays, even with a candidate near the track.
    for (int n = 0; n < 5; ++n)
    {
        const auto d = tracker.update(
            kAp, 1.0 + 0.1 * n, mrpt::math::TPose2D(0, 0, 0), rx,
            {{at(rx, 10), 1.0}, {at(rx, -40), 0.9}}, 2 * kDeg);
        EXPECT_EQ(d.chosen, 0u);
    }
    // After maxMisses misses in a row the track has started over at 10°.
    const auto d =
        tracker.update(kAp, 1.6, mrpt::math::TPose2D(0, 0, 0), rx, {{at(rx, 11), 1.0}}, 2 * kDeg);
    EXPECT_FALSE(d.miss);
    EXPECT_LT(angleDistance(d.predicted_rad, at(rx, 11)), 3 * kDeg);
}

TEST(BearingTracker, ATrackAtTheWrongEndfireGivesWayToSureWindows)
{
    // Development room 48's fourth AP, at 60–70° from broadside: some windows found it there
    // and were sure, with the other endfire (−90°) a second candidate. A track at −90° swapped
    // them for −90° and each swap confirmed it (17 % of that AP's bearings beyond 30°, 3.4 %
    // without tracking).
    const AntennaArray rx = test::loadArray("rt-ac86u");
    BearingTracker tracker;
    const mrpt::math::TPose2D still(0, 0, 0);
    double t = 0;
    // Windows that can't tell start no track: the first sure window does.
    for (int n = 0; n < 5; ++n, t += 0.02)
    {
        const auto d =
            tracker.update(kAp, t, still, rx, {{at(rx, -90), 1.0}, {at(rx, 70), 0.95}}, 65 * kDeg);
        EXPECT_EQ(d.chosen, 0u);
        EXPECT_EQ(d.support, 0) << "an ambiguous window started a track";
    }
    // A track the sure windows built at the other endfire (a reflection near it, say).
    for (int n = 0; n < 10; ++n, t += 0.02)
        tracker.update(kAp, t, still, rx, {{at(rx, -88), 1.0}}, 5 * kDeg);
    // Sure windows at 70°, the other endfire their second candidate: kept, not swapped; after
    // maxMisses of them the track starts over there.
    const unsigned misses = tracker.options().maxMisses;
    for (unsigned n = 0; n < misses; ++n, t += 0.02)
    {
        const auto d =
            tracker.update(kAp, t, still, rx, {{at(rx, 70), 1.0}, {at(rx, -90), 0.97}}, 5 * kDeg);
        EXPECT_EQ(d.chosen, 0u) << "a sure window was swapped for the track's endfire";
        EXPECT_TRUE(d.miss);
    }
    const auto d =
        tracker.update(kAp, t, still, rx, {{at(rx, 71), 1.0}, {at(rx, -90), 0.97}}, 5 * kDeg);
    EXPECT_FALSE(d.miss);
    EXPECT_LT(angleDistance(d.predicted_rad, at(rx, 70)), 3 * kDeg);
    // Now a window that can't tell and puts the transmitter at −90° is swapped back to the
    // track's side once the track is established again.
    for (int n = 0; n < 3; ++n, t += 0.02)
        tracker.update(kAp, t, still, rx, {{at(rx, 70), 1.0}}, 5 * kDeg);
    const auto swapped =
        tracker.update(kAp, t, still, rx, {{at(rx, -90), 1.0}, {at(rx, 89), 0.97}}, 65 * kDeg);
    EXPECT_EQ(swapped.chosen, 1u);
}
