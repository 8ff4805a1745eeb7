// Offline == live: a capture replayed through Debian's rawlog-grabber with bearing_algorithm set
// (share/rawlog-grabber/csi_live_bearings.ini) gives, after every CSI frame, the bearing that
// csi-pcap2rawlog + csi-bearings compute offline from the same capture.
#include <gtest/gtest.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/obs/CObservationBearingRange.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>

#include <filesystem>
#include <map>
#include <sstream>

#include "GrabberRun.h"
#include "TestSupport.h"

using namespace mrpt_wifi;

namespace
{
struct Bearing
{
    std::string label;
    double aoa, aoaStd, quality;
    std::string algorithm;
    bool operator==(const Bearing& b) const
    {
        return label == b.label && aoa == b.aoa && aoaStd == b.aoaStd && quality == b.quality &&
               algorithm == b.algorithm;
    }
};

/** Per CSI frame (transmitter, sequence number), in file order: the bearings that follow it. */
using Frames = std::vector<std::pair<std::string, std::vector<Bearing>>>;

Frames framesWithBearings(const std::vector<mrpt::serialization::CSerializable::Ptr>& objs)
{
    Frames out;
    for (const auto& o : objs)
    {
        if (auto c = std::dynamic_pointer_cast<CObservationWiFiCSI>(o))
        {
            out.emplace_back(
                c->transmitter.asString() + "#" + std::to_string(c->sequenceNumber),
                std::vector<Bearing>{});
            continue;
        }
        if (out.empty()) continue;
        if (auto b = std::dynamic_pointer_cast<CObservationWiFiBearing>(o))
            out.back().second.push_back(
                {b->sensorLabel + " " + b->transmitter.asString() + "#" +
                     std::to_string(b->framesUsed),
                 b->aoa_rad, b->aoaStd_rad, b->quality, b->algorithm});
        else if (auto br = std::dynamic_pointer_cast<mrpt::obs::CObservationBearingRange>(o))
            out.back().second.push_back(
                {br->sensorLabel, br->sensedData.empty() ? 0.0 : br->sensedData[0].yaw, 0, 0,
                 "range"});
    }
    return out;
}
}  // namespace

TEST(LiveBearingsGrabber, ReplayGivesTheBearingsCsiBearingsComputesOffline)
{
    test::TempDir tmp;
    const std::string pcap = test::sourceDir() + "/share/samples/sample_4x4_80mhz.pcap";
    const std::string algo = "aoa_only";
    const auto ini = test::deriveGrabberIni(
        "csi_live_bearings.ini",
        {{"router_control", "false"},
         {"source", "pcap"},
         {"pcap_file", pcap},
         {"router_address", ""},
         {"status_period", "1"},
         {"sensorLabel", "CSI"},
         {"pose_x", "0"},
         {"pose_z", "0"},
         {"bearing_algorithm", algo},
         {"rawlog_prefix", "live"}},
        tmp.file("live.ini"));
    const auto grab = test::run(
        "cd " + tmp.path().string() + " && (sleep 3; echo) | timeout 120 rawlog-grabber -p " +
        test::libDir() + "/libmrpt_wifi_sensor.so " + ini);
    ASSERT_EQ(grab.exitCode, 0) << grab.output;
    // The status line reports the live bearings.
    EXPECT_NE(grab.output.find("bearings "), std::string::npos) << grab.output;
    EXPECT_NE(grab.output.find("latency p50"), std::string::npos) << grab.output;
    EXPECT_NE(grab.output.find("no bearing_calibration"), std::string::npos) << grab.output;

    std::string liveRawlog;
    for (const auto& e : std::filesystem::directory_iterator(tmp.path()))
        if (e.path().extension() == ".rawlog") liveRawlog = e.path().string();
    ASSERT_FALSE(liveRawlog.empty()) << grab.output;

    const auto conv = test::run(
        test::binDir() + "/csi-pcap2rawlog " + pcap + " " + tmp.file("off.rawlog") +
        " --sensor-label CSI");
    ASSERT_EQ(conv.exitCode, 0) << conv.output;
    const auto off = test::run(
        test::binDir() + "/csi-bearings -q -a " + algo + " " + tmp.file("off.rawlog") + " " +
        tmp.file("off_bearings.rawlog"));
    ASSERT_EQ(off.exitCode, 0) << off.output;

    const auto live = framesWithBearings(test::readRawlog(liveRawlog));
    const auto offline = framesWithBearings(test::readRawlog(tmp.file("off_bearings.rawlog")));
    ASSERT_EQ(offline.size(), 22u);
    // rawlog-grabber 2.5.8 keeps the last queued observation unwritten at exit.
    ASSERT_GE(live.size(), 21u) << grab.output;
    // Bearings are per transmitter, so frames of different transmitters that complete together
    // may be written in either order: match frames by transmitter and sequence number.
    std::map<std::string, std::vector<Bearing>> offlineOf(offline.begin(), offline.end());
    ASSERT_EQ(offlineOf.size(), offline.size());
    size_t bearings = 0;
    for (size_t i = 0; i + 1 < live.size(); ++i)  // the last frame may have lost its bearing
    {
        const auto it = offlineOf.find(live[i].first);
        ASSERT_NE(it, offlineOf.end()) << live[i].first;
        EXPECT_EQ(live[i].second, it->second) << "frame " << i << " " << live[i].first;
        bearings += live[i].second.size();
    }
    EXPECT_GE(bearings, 2 * 18u);  // a bearing and its bearing-range for (almost) every frame
}
