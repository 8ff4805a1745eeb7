/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <gtest/gtest.h>
#include <mrpt_wifi/localization/DeviceMapper.h>

#include "SyntheticWorld.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;
using namespace mrpt_wifi::loctest;

namespace
{
World iotWorld(double outliers, double duration = 120)
{
    WorldOptions o;
    o.aod = false;
    o.outliers = outliers;
    o.duration_s = duration;
    o.aoaStd = 0.07;
    return makeWorld(makeAps({{1.0, 4.6, 0}, {9.5, 4.5, 0}, {6.0, 0.3, 0}}), o);
}
}  // namespace

TEST(IotMapTriangulation, LocalizesDevicesWithOutliersAndMirrors)
{
    const auto w = iotWorld(0.1);
    InputWarnings warn;
    const auto rays = raysFromBearings(w.bearings, w.truth, &warn);
    EXPECT_EQ(warn.outsideTrajectory, 0u);
    ASSERT_EQ(rays.size(), 3u);
    for (const auto& [mac, r] : rays)
    {
        const auto d = triangulateDevice(r, DeviceMapOptions());
        const auto* t = w.aps.find(mac);
        ASSERT_TRUE(d.localized) << d.note;
        EXPECT_LT(std::hypot(d.x - t->pose.x, d.y - t->pose.y), 0.3) << t->name;
        EXPECT_GT(d.cov[0], 0);
        EXPECT_GT(d.cov[2], 0);
        EXPECT_LT(d.inliers, d.rays);  // the outliers were recognised as such
    }
}

TEST(IotMapTriangulation, MirrorCandidatesAreUsedNotDiscarded)
{
    // The robot's linear array reports the front-half candidate first; for a device behind the
    // robot that one is the ghost. Mirror-aware triangulation explains (almost) every ray; taking
    // the first candidate at face value leaves the rays from behind as outliers.
    const auto w = iotWorld(0.0);
    auto rays = raysFromBearings(w.bearings, w.truth);
    const auto& [mac, r] = *rays.begin();
    auto naive = r;
    for (auto& x : naive) x.ambiguous = false;
    const auto* t = w.aps.find(mac);
    const auto good = triangulateDevice(r, {});
    const auto bad = triangulateDevice(naive, {});
    EXPECT_LT(std::hypot(good.x - t->pose.x, good.y - t->pose.y), 0.3);
    EXPECT_GT(good.inliers, 0.95 * good.rays) << good.inliers << "/" << good.rays;
    EXPECT_LT(bad.inliers, 0.8 * bad.rays) << bad.inliers << "/" << bad.rays;
}

TEST(IotMapBadInput, TooFewBearingsAndOutsideTrajectory)
{
    auto w = iotWorld(0.0, 10);
    std::vector<BearingRay> few;
    const auto rays = raysFromBearings(w.bearings, w.truth);
    few.assign(rays.begin()->second.begin(), rays.begin()->second.begin() + 3);
    const auto d = triangulateDevice(few, {});
    EXPECT_FALSE(d.localized);
    EXPECT_NE(d.note.find("only 3 bearings"), std::string::npos) << d.note;

    for (auto& b : w.bearings) b.t += 100;  // after the trajectory ends
    InputWarnings warn;
    EXPECT_TRUE(raysFromBearings(w.bearings, w.truth, &warn).empty());
    EXPECT_EQ(warn.outsideTrajectory, w.bearings.size());
}
