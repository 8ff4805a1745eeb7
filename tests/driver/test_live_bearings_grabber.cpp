// Offline == live: a capture replayed through Debian's rawlog-grabber with bearing_algorithm set
// (share/rawlog-grabber/csi_live_bearings.ini) gives, after every CSI frame, the bearing that
// csi-pcap2rawlog + csi-bearings compute offline from the same capture.
#include <gtest/gtest.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/obs/CObservationBearingRange.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/obs/ChainStates.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
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

TEST(LiveBearingsGrabber, RecordsTheChainJumpStatesOfEveryFrame)
{
    // loop.yaml with its chains switching among 3 delay states (3 ns apart) at 0.3 Hz, as a
    // pcap, replayed through rawlog-grabber at 10× its pace: every recorded frame carries its
    // chains' delays and states, the states follow the simulator's (ids mapped by majority),
    // and the status line counts the changes.
    test::TempDir tmp;
    std::ifstream in(test::sourceDir() + "/share/scenarios/loop.yaml");
    std::stringstream text;
    text << in.rdbuf();
    const std::string shipped =
        "antenna_jumps: {enabled: true, states: 3, step_ns: 3, rate_hz: 0.05}";
    std::string scenario = text.str();
    const size_t at = scenario.find(shipped);
    ASSERT_NE(at, std::string::npos) << "loop.yaml's antenna_jumps line changed";
    scenario.replace(
        at, shipped.size(),
        "antenna_jumps: {enabled: true, states: 3, step_ns: 3, rate_hz: 0.3, state_phase: true}");
    // The scenario names its arrays relative to share/scenarios.
    std::filesystem::create_directories(tmp.file("scenarios"));
    std::filesystem::create_directory_symlink(
        test::sourceDir() + "/share/arrays", tmp.file("arrays"));
    std::ofstream(tmp.file("scenarios/jumpy.yaml")) << scenario;
    const auto sim = test::run(
        test::binDir() + "/wifi-sim -q -s 3 -d 20 " + tmp.file("scenarios/jumpy.yaml") +
        " /dev/null --pcap " + tmp.file("jumpy.pcap") + " -t " + tmp.file("truth"));
    ASSERT_EQ(sim.exitCode, 0) << sim.output;

    const auto ini = test::deriveGrabberIni(
        "csi_receiver.ini",
        {{"router_control", "false"},
         {"source", "pcap"},
         {"pcap_file", tmp.file("jumpy.pcap")},
         {"pcap_speed", "10"},
         {"router_address", ""},
         {"status_period", "0.5"},
         {"rawlog_prefix", "jumpy"}},
        tmp.file("jumpy.ini"));
    const auto rec = test::runGrabber(tmp, ini, 4.0);
    ASSERT_EQ(rec.exitCode, 0) << rec.log;
    ASSERT_GT(rec.frames.size(), 50u) << rec.log;

    // The simulator's states per (transmitter, sequence number).
    std::map<std::string, std::string> truth;
    {
        std::ifstream f(tmp.file("truth/frames.csv"));
        std::string line;
        std::getline(f, line);
        while (std::getline(f, line))
        {
            std::vector<std::string> col;
            std::stringstream ss(line);
            for (std::string c; std::getline(ss, c, ',');) col.push_back(c);
            truth[col[3] + "#" + col[4]] = col.back();
        }
    }
    size_t withStates = 0, classified = 0, agree = 0;
    std::map<std::pair<int, std::string>, std::map<int, size_t>> votes;  // (chain, truth) → id
    std::vector<std::pair<std::string, std::vector<uint8_t>>> seen;
    for (const auto& f : rec.frames)
    {
        if (f->chainState.size() != 4 || f->chainDelay_ns.size() != 4) continue;
        ++withStates;
        const auto it =
            truth.find(f->transmitter.asString() + "#" + std::to_string(f->sequenceNumber));
        ASSERT_NE(it, truth.end()) << f->transmitter.asString() << " " << f->sequenceNumber;
        seen.emplace_back(it->second, f->chainState);
    }
    EXPECT_GE(double(withStates), 0.99 * double(rec.frames.size()));
    // Split "a|b|c|d" into per-chain true states.
    const auto chainOf = [](const std::string& s, int i)
    {
        std::vector<std::string> p;
        std::stringstream ss(s);
        for (std::string c; std::getline(ss, c, '|');) p.push_back(c);
        return p.at(size_t(i));
    };
    for (const auto& [t, ids] : seen)
        for (int i = 1; i < 4; ++i)
            if (ids[size_t(i)] != kUnknownChainState) votes[{i, chainOf(t, i)}][ids[size_t(i)]]++;
    std::map<std::pair<int, std::string>, int> idOf;
    for (const auto& [key, v] : votes)
        idOf[key] = std::max_element(
                        v.begin(), v.end(), [](auto& a, auto& b) { return a.second < b.second; })
                        ->first;
    std::set<std::pair<int, std::string>> trueStates;
    for (const auto& [t, ids] : seen)
        for (int i = 1; i < 4; ++i)
        {
            trueStates.insert({i, chainOf(t, i)});
            if (ids[size_t(i)] == kUnknownChainState) continue;
            ++classified;
            agree += idOf[{i, chainOf(t, i)}] == ids[size_t(i)];
        }
    std::cout << seen.size() << " frames with states; " << classified
              << " chain-frames classified, " << agree << " in the right state\n";
    EXPECT_GT(trueStates.size(), 3u) << "the simulator switched no chain in the recorded span";
    EXPECT_GE(double(classified), 0.7 * 3 * double(seen.size()));
    EXPECT_GE(double(agree), 0.9 * double(classified));
    EXPECT_NE(rec.log.find("chain state changes"), std::string::npos) << rec.log;

    // RawLogViewer's text shows them.
    std::ostringstream d;
    rec.frames.back()->getDescriptionAsText(d);
    EXPECT_NE(d.str().find("Receive chain states"), std::string::npos) << d.str();
}
