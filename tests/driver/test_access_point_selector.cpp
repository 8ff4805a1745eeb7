#include <gtest/gtest.h>
#include <mrpt_wifi/sensor/AccessPointSelector.h>

using namespace mrpt_wifi;

namespace
{
ScannedAccessPoint ap(const char* mac, int rssi, const char* channel, const char* ssid = "lab")
{
    ScannedAccessPoint a;
    a.bssid = MacAddress::fromString(mac);
    a.rssi_dBm = rssi;
    a.chanspec = Chanspec::fromString(channel);
    a.ssid = ssid;
    return a;
}

CObservationWiFiScan scanOf(std::vector<ScannedAccessPoint> aps)
{
    CObservationWiFiScan s;
    s.accessPoints = std::move(aps);
    return s;
}
}  // namespace

TEST(AccessPointSelector, LocksOntoTheStrongestThenHoldsWithHysteresis)
{
    AccessPointSelectorOptions o;
    o.minRssiGain_dB = 6;
    o.minDwell_s = 10;
    AccessPointSelector sel(o);
    const char *A = "02:00:00:00:00:0a", *B = "02:00:00:00:00:0b";

    auto d = sel.onScan(
        scanOf({ap(A, -50, "155/80"), ap(B, -60, "42/80"), ap("02:00:00:00:00:0c", -30, "6")}), 0);
    ASSERT_TRUE(d);  // 2.4 GHz AP ignored although strongest
    EXPECT_EQ(d->target.bssid.asString(), A);
    EXPECT_NE(d->reason.find("initial lock"), std::string::npos) << d->reason;

    // B slightly stronger: not enough gain.
    EXPECT_FALSE(sel.onScan(scanOf({ap(A, -55, "155/80"), ap(B, -52, "42/80")}), 20));
    // B much stronger but the lock is too young? No: 30 s > 10 s dwell → switch.
    // First make it too young: a fresh lock can't flip back at once.
    d = sel.onScan(scanOf({ap(A, -70, "155/80"), ap(B, -50, "42/80")}), 30);
    ASSERT_TRUE(d);
    EXPECT_EQ(d->target.bssid.asString(), B);
    EXPECT_EQ(d->target.chanspec.centerChannel, 42);
    EXPECT_NE(d->reason.find("by 20 dB"), std::string::npos) << d->reason;
    // A is back stronger right after: dwell not reached → stay on B (no ping-pong).
    EXPECT_FALSE(sel.onScan(scanOf({ap(A, -40, "155/80"), ap(B, -60, "42/80")}), 32));
    EXPECT_EQ(sel.locked()->bssid.asString(), B);
    // Noise around equal levels never switches.
    for (int i = 0; i < 20; ++i)
        EXPECT_FALSE(sel.onScan(
            scanOf({ap(A, -60 + (i % 3), "155/80"), ap(B, -58 - (i % 4), "42/80")}), 33 + i));
}

TEST(AccessPointSelector, DropsALostAccessPointAfterMissingScans)
{
    AccessPointSelector sel;
    const char *A = "02:00:00:00:00:0a", *B = "02:00:00:00:00:0b";
    ASSERT_TRUE(sel.onScan(scanOf({ap(A, -50, "155/80")}), 0));
    EXPECT_FALSE(sel.onScan(scanOf({ap(B, -75, "42/80")}), 1));   // missing once: wait
    const auto d = sel.onScan(scanOf({ap(B, -75, "42/80")}), 2);  // twice: move on
    ASSERT_TRUE(d);
    EXPECT_EQ(d->target.bssid.asString(), B);
    EXPECT_NE(d->reason.find("missing"), std::string::npos);
}

TEST(AccessPointSelector, RespectsMinimumRssiAndSsid)
{
    AccessPointSelectorOptions o;
    o.minRssi_dBm = -80;
    o.ssidFilter = "robots";
    AccessPointSelector sel(o);
    EXPECT_FALSE(sel.onScan(scanOf({ap("02:00:00:00:00:01", -85, "155/80", "robots")}), 0));
    EXPECT_FALSE(sel.onScan(scanOf({ap("02:00:00:00:00:02", -40, "155/80", "guests")}), 1));
    EXPECT_TRUE(sel.onScan(scanOf({ap("02:00:00:00:00:03", -70, "42/80", "robots")}), 2));
}

TEST(AccessPointSelector, ChannelScheduleFromAScan)
{
    // channel_schedule = scan: each channel once, in channel order, within the band and limits.
    AccessPointSelectorOptions o;
    o.minRssi_dBm = -80;
    o.ssidFilter = "lab";
    const auto channels = channelsFromScan(
        scanOf(
            {ap("02:00:00:00:00:01", -50, "155/80"), ap("02:00:00:00:00:02", -60, "42/80"),
             ap("02:00:00:00:00:03", -55, "157/80"),  // 155/80 again (control channel 157)
             ap("02:00:00:00:00:04", -40, "6"),       // 2.4 GHz: another band
             ap("02:00:00:00:00:05", -85, "106/80"),  // too weak
             ap("02:00:00:00:00:06", -45, "58/80", "guest")}),
        o);
    ASSERT_EQ(channels.size(), 2u);
    EXPECT_EQ(channels[0].asString(), "42/80");
    EXPECT_EQ(channels[1].asString(), "155/80");
    o.band = WifiBand::Band2G4;
    const auto g = channelsFromScan(scanOf({ap("02:00:00:00:00:04", -40, "6")}), o);
    ASSERT_EQ(g.size(), 1u);
    EXPECT_EQ(g[0].centerChannel, 6);
}
