// End to end with real parts: Debian's rawlog-grabber loads libmrpt_wifi_sensor.so with a
// share/ config, configures the emulated RT-AC86U through a real sshd on 127.0.0.1 (the
// emulator's wl / nexutil / makecsiparams shims are the remote commands), and records the CSI
// the emulator sends to 127.0.0.1.
#include <gtest/gtest.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/CObservationWiFiScan.h>
#include <mrpt_wifi/sensor/CsiFileReader.h>

#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "EmulatorProcess.h"
#include "GrabberRun.h"
#include "SshdFixture.h"

using namespace mrpt_wifi;

namespace
{
std::string scenario(const std::string& name)
{
    return test::sourceDir() + "/share/scenarios/" + name + ".yaml";
}

std::map<std::string, std::string> sshKeys(const test::SshdFixture& sshd)
{
    return {
        {"login_host", "127.0.0.1"},
        {"login_port", std::to_string(sshd.port())},
        {"login_user", sshd.user()},
        {"login_identity_file", sshd.clientKey()},
        {"login_known_hosts", sshd.knownHosts()},
        {"router_address", "127.0.0.1"},
        {"udp_bind_address", "127.0.0.1"},
        {"status_period", "1"}};
}
}  // namespace

TEST(GrabberEmulator, RecordsCsiThroughSshConfiguredRouter)
{
    test::TempDir tmp;
    const uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);
    // 4 APs x 100 frames/s of 16 datagrams once the grabber has configured the router; the
    // emulator records what it sends and stops sending after 16,000 datagrams (2.5 s of CSI).
    test::EmulatorProcess emu(
        {"--scenario", scenario("kidnapped"), "--fault-seed", "3", "--record-sent",
         tmp.file("sent.pcap"), "--max-datagrams", "16000"},
        port, 60);
    ASSERT_TRUE(emu.ready()) << emu.log();
    test::SshdFixture sshd(emu.toolsDir());
    MRPT_WIFI_REQUIRE_SSHD(sshd);

    auto keys = sshKeys(sshd);
    keys["udp_port"] = std::to_string(port);
    keys["channel"] = "155/80";
    keys["rawlog_prefix"] = "rec";
    // Core 2 disabled (makecsiparams -C 0xb), as on routers with a 3-antenna set-up.
    keys["core_mask"] = "0xb";
    const auto ini = test::deriveGrabberIni("csi_receiver.ini", keys, tmp.file("grab.ini"));
    const auto rec = test::runGrabber(tmp, ini, 6.0);
    emu.stop();  // closes the record of what was sent
    ASSERT_EQ(rec.exitCode, 0) << rec.log;
    EXPECT_NE(rec.log.find("router configured: CSI on 155/80"), std::string::npos) << rec.log;

    // How many frames a wall-clock run records depends on how busy the machine is (the ssh
    // set-up eats into the 6 s): compare with what the emulator sent instead. Every frame it
    // sent up to the last one recorded must be there, complete (no loss was injected). The
    // only allowance is the kernel's socket buffer overflowing on a busy machine: the drops the
    // sensor reported, plus 1 % for those after its last status line.
    ASSERT_FALSE(rec.frames.empty())
        << rec.log.substr(rec.log.size() > 4000 ? rec.log.size() - 4000 : 0);
    const auto sent = test::decodeSentFrames(tmp.file("sent.pcap"), port);
    const auto cmp = test::compareWithSent(rec.frames, sent);
    EXPECT_EQ(cmp.neverSent, 0u);
    std::map<std::string, size_t> perTx;
    size_t incomplete = 0;
    for (const auto& f : rec.frames)
    {
        ASSERT_EQ(f->chanspec.centerChannel, 155);
        ASSERT_EQ(f->chanspec.bandwidthMHz, 80);
        ASSERT_EQ(f->sensorLabel, "WIFI_CSI");
        incomplete += !f->isComplete();
        ++perTx[f->transmitter.asString()];
        EXPECT_EQ(f->nTx, 4);
        EXPECT_EQ(f->rxCores, (std::vector<uint8_t>{0, 1, 3}));
    }
    // The receiver listened before the router was configured: the first frames sent count too.
    const size_t missing = cmp.firstRecorded + cmp.missing;
    const size_t sentUpToLast = cmp.firstRecorded + cmp.sentInSpan;
    const size_t allowance = test::lastReportedKernelDrops(rec.log) + sentUpToLast / 100;
    EXPECT_LE(missing + incomplete, allowance)
        << rec.frames.size() << " frames recorded, " << missing << " of the " << sentUpToLast
        << " sent up to the last recorded one missing, " << incomplete << " incomplete";
    EXPECT_EQ(perTx.size(), 4u);
    // The pose from the .ini (pose_x = 0.10, pose_z = 0.40).
    EXPECT_NEAR(rec.frames.front()->sensorPose.x(), 0.10, 1e-9);
    EXPECT_NEAR(rec.frames.front()->sensorPose.z(), 0.40, 1e-9);
    std::cout << rec.frames.size() << " frames recorded of " << sent.size() << " sent (" << missing
              << " missing up to the last recorded, " << incomplete << " incomplete)\n";
}

TEST(GrabberEmulator, InjectedLossAndCorruptionAreCountedAndCaptureGoesOn)
{
    test::TempDir tmp;
    const uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);
    test::EmulatorProcess emu(
        {"--scenario", scenario("kidnapped"), "--fault-seed", "5", "--loss", "0.02", "--corrupt",
         "0.02", "--duplicate", "0.01", "--reorder", "0.01", "--preconfigured", "155/80",
         "--record-sent", tmp.file("sent.pcap"), "--max-datagrams", "40000"},
        port, 60);
    ASSERT_TRUE(emu.ready()) << emu.log();
    // No router control here: a receiver that only listens (preconfigured router).
    const auto ini = test::deriveGrabberIni(
        "csi_receiver.ini",
        {{"router_control", "false"},
         {"udp_port", std::to_string(port)},
         {"udp_bind_address", "127.0.0.1"},
         {"router_address", "127.0.0.1"},
         {"status_period", "1"},
         {"rawlog_prefix", "lossy"}},
        tmp.file("grab.ini"));
    const auto rec = test::runGrabber(tmp, ini, 4.0);
    emu.stop();  // closes the record of what was sent
    ASSERT_EQ(rec.exitCode, 0) << rec.log;
    // Capture goes on through the faults: of the frames the emulator sent (after its faults)
    // while the grabber recorded, at most 2 % are missing (a frame is lost only when all its
    // datagrams are; the rest is the kernel's socket buffer on a busy machine, as reported).
    ASSERT_FALSE(rec.frames.empty()) << rec.log;
    const auto cmp =
        test::compareWithSent(rec.frames, test::decodeSentFrames(tmp.file("sent.pcap"), port));
    EXPECT_LE(cmp.missing, test::lastReportedKernelDrops(rec.log) + cmp.sentInSpan / 50)
        << cmp.missing << " of " << cmp.sentInSpan << " sent frames not recorded";
    std::cout << rec.frames.size() << " frames recorded, " << cmp.missing << " of "
              << cmp.sentInSpan << " sent in their span missing, " << cmp.neverSent
              << " never sent\n";
    size_t incomplete = 0;
    for (const auto& f : rec.frames) incomplete += !f->isComplete();
    // 2% datagram loss on 16-datagram frames: ~28% of frames miss a pair; corruption adds more.
    const double fraction = double(incomplete) / double(rec.frames.size());
    EXPECT_GT(fraction, 0.15);
    EXPECT_LT(fraction, 0.65);
    // The status lines count what was rejected, duplicated and reordered.
    EXPECT_TRUE(std::regex_search(rec.log, std::regex("rejected [1-9][0-9]*")))
        << rec.log.substr(0, 3000);
    EXPECT_TRUE(std::regex_search(rec.log, std::regex("duplicates dropped [1-9][0-9]*")));
}

TEST(GrabberEmulator, WrongKeyOrUnreachableRouterIsAClearErrorNotAHang)
{
    test::TempDir tmp;
    const uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);
    test::EmulatorProcess emu({"--scenario", scenario("kidnapped")}, port, 60);
    ASSERT_TRUE(emu.ready()) << emu.log();
    test::SshdFixture sshd(emu.toolsDir());
    MRPT_WIFI_REQUIRE_SSHD(sshd);

    auto keys = sshKeys(sshd);
    keys["udp_port"] = std::to_string(port);
    keys["login_identity_file"] = sshd.otherKey();  // not authorised on the router
    keys["rawlog_prefix"] = "wrongkey";
    const auto t0 = std::chrono::steady_clock::now();
    auto rec = test::runGrabber(
        tmp, test::deriveGrabberIni("csi_receiver.ini", keys, tmp.file("a.ini")), 3.0);
    EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(30));
    EXPECT_NE(rec.log.find("authentication failed"), std::string::npos) << rec.log;

    keys["login_identity_file"] = sshd.clientKey();
    keys["login_port"] = std::to_string(test::freeLoopbackPort());  // nobody there
    keys["login_connect_timeout"] = "2";
    keys["rawlog_prefix"] = "unreachable";
    rec = test::runGrabber(
        tmp, test::deriveGrabberIni("csi_receiver.ini", keys, tmp.file("b.ini")), 3.0);
    EXPECT_NE(rec.log.find("router unreachable"), std::string::npos) << rec.log;
}

TEST(GrabberEmulator, AutomaticModeSwitchesOnceWhenTheRobotRoams)
{
    test::TempDir tmp;
    const uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);
    // 120 simulated seconds at 8x: the robot drives from the west AP to the east AP.
    test::EmulatorProcess emu(
        {"--scenario", scenario("roaming"), "--speed", "8", "--scan-time", "0.2", "--retune-delay",
         "0.02"},
        port, 60);
    ASSERT_TRUE(emu.ready()) << emu.log();
    test::SshdFixture sshd(emu.toolsDir());
    MRPT_WIFI_REQUIRE_SSHD(sshd);
    auto keys = sshKeys(sshd);
    keys["udp_port"] = std::to_string(port);
    keys["channel"] = "155/80";
    keys["scan_period"] = "1";
    keys["scan_wait"] = "0.3";
    keys["auto_min_dwell_s"] = "2";
    keys["rawlog_prefix"] = "auto";
    const auto rec = test::runGrabber(
        tmp, test::deriveGrabberIni("csi_auto_channel.ini", keys, tmp.file("auto.ini")), 14.0);
    ASSERT_EQ(rec.exitCode, 0) << rec.log;
    // Locks onto the west AP first (the robot starts there), then switches exactly once.
    const std::regex switchRe("channel switch to ([0-9]+/[0-9]+): (.*)");
    std::vector<std::string> switches;
    for (std::sregex_iterator it(rec.log.begin(), rec.log.end(), switchRe), end; it != end; ++it)
        switches.push_back((*it)[1].str() + " | " + (*it)[2].str());
    ASSERT_EQ(switches.size(), 2u)
        << rec.log.substr(rec.log.size() > 6000 ? rec.log.size() - 6000 : 0);
    EXPECT_EQ(switches[0].rfind("42/80 | initial lock", 0), 0u) << switches[0];
    EXPECT_EQ(switches[1].rfind("155/80 |", 0), 0u) << switches[1];
    EXPECT_FALSE(rec.scans.empty());
    bool sawWest = false, sawEast = false;
    for (const auto& f : rec.frames)
    {
        sawWest |= f->chanspec.centerChannel == 42;
        sawEast |= f->chanspec.centerChannel == 155;
    }
    EXPECT_TRUE(sawWest && sawEast);
    // The downtime of each switch is measured; target < 200 ms. (The first "first frame" line
    // is the initial set-up, which includes connecting and loading the module.)
    std::string lastDowntime;
    const std::regex downtimeRe("first frame on 155/80 ([0-9]+) ms after the switch request");
    for (std::sregex_iterator it(rec.log.begin(), rec.log.end(), downtimeRe), end; it != end; ++it)
        lastDowntime = (*it)[1].str();
    ASSERT_FALSE(lastDowntime.empty()) << rec.log;
    EXPECT_LT(std::stoi(lastDowntime), 200);
    ::testing::Test::RecordProperty("switch_downtime_ms", lastDowntime);
}

TEST(GrabberEmulator, CsiRouterSwitchMeasuresTheDowntime)
{
    const uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);
    test::EmulatorProcess emu(
        {"--scenario", scenario("roaming"), "--preconfigured", "155/80"}, port, 60);
    ASSERT_TRUE(emu.ready()) << emu.log();
    test::SshdFixture sshd(emu.toolsDir());
    MRPT_WIFI_REQUIRE_SSHD(sshd);
    const std::string base = test::binDir() + "/csi-router --host 127.0.0.1 --port " +
                             std::to_string(sshd.port()) + " --user " + sshd.user() + " -i " +
                             sshd.clientKey() + " --known-hosts " + sshd.knownHosts() + " ";
    auto r = test::run(base + "status");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("channel 155/80"), std::string::npos) << r.output;
    const std::string measure = " --measure --measure-timeout 3 --config " + test::sourceDir() +
                                "/share/rawlog-grabber/csi_receiver.ini";
    // csi_receiver.ini listens on 5500; point it at the emulator's port via a derived copy.
    test::TempDir tmp;
    const auto ini = test::deriveGrabberIni(
        "csi_receiver.ini", {{"udp_port", std::to_string(port)}, {"udp_bind_address", "127.0.0.1"}},
        tmp.file("r.ini"));
    r = test::run(base + "switch 36/80 --measure --measure-timeout 3 --config " + ini);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(
        r.output, m, std::regex("switch downtime \\(request -> first frame\\): ([0-9.]+) ms")))
        << r.output;
    EXPECT_LT(std::stod(m[1]), 200.0) << r.output;
    ::testing::Test::RecordProperty("csi_router_switch_downtime_ms", m[1].str());
    r = test::run(base + "status");
    EXPECT_NE(r.output.find("channel 42/80"), std::string::npos) << r.output;
    r = test::run(base + "scan");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("02:00:00:00:05:01"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("2 access points"), std::string::npos) << r.output;
}

TEST(GrabberEmulator, PcapSourceReplaysACaptureAtItsRecordedPace)
{
    // source = pcap: the same data path fed from a capture (here the project's sample: 22
    // frames over ~50 ms), through Debian's rawlog-grabber.
    test::TempDir tmp;
    const auto ini = test::deriveGrabberIni(
        "csi_receiver.ini",
        {{"router_control", "false"},
         {"source", "pcap"},
         {"pcap_file", test::sourceDir() + "/share/samples/sample_4x4_80mhz.pcap"},
         {"router_address", "10.10.10.10"},
         {"rawlog_prefix", "replay"}},
        tmp.file("replay.ini"));
    const auto rec = test::runGrabber(tmp, ini, 3.0);
    ASSERT_EQ(rec.exitCode, 0) << rec.log;
    EXPECT_NE(rec.log.find("replay of"), std::string::npos) << rec.log;
    // rawlog-grabber 2.5.8 keeps the last queued observation unwritten at exit.
    ASSERT_GE(rec.frames.size(), 21u) << rec.log;
    ASSERT_LE(rec.frames.size(), 22u);
    for (const auto& f : rec.frames)
    {
        EXPECT_TRUE(f->isComplete());
        EXPECT_EQ(f->routerAddress, "10.10.10.10");
    }
    // Replayed at the recorded pace: the frames span what the capture spans (~50 ms), on the
    // replay's clock (now), not the capture's (2023).
    double t0 = 1e300, t1 = 0;
    for (const auto& f : rec.frames)
        t0 = std::min(t0, mrpt::Clock::toDouble(f->timestamp)),
        t1 = std::max(t1, mrpt::Clock::toDouble(f->timestamp));
    EXPECT_GT(t0, 1.7e9 + 3.0e7);
    EXPECT_LT(t1 - t0, 0.2);
    EXPECT_GT(t1 - t0, 0.02);
}

/** share/scenarios/hopping.yaml (one AP on each of 42/80, 155/80 and 6/20) on the emulator
 *  with `emulatorArgs`, its router behind a loopback sshd, recorded by rawlog-grabber for
 *  `seconds` with csi_channel_schedule.ini and `keys`. */
struct HoppingRecording
{
    test::TempDir tmp;
    uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);
    test::EmulatorProcess emu;
    test::SshdFixture sshd;
    test::GrabberRecording rec;
    std::string tail;  //!< the end of the grabber's log, for failure messages

    explicit HoppingRecording(const std::vector<std::string>& emulatorArgs)
        : emu(withScenario(emulatorArgs), port, 60), sshd(emu.toolsDir())
    {
    }
    static std::vector<std::string> withScenario(std::vector<std::string> args)
    {
        args.insert(args.begin(), {"--scenario", scenario("hopping")});
        return args;
    }
    void record(std::map<std::string, std::string> keys, double seconds)
    {
        for (const auto& [k, v] : sshKeys(sshd)) keys.emplace(k, v);
        keys["udp_port"] = std::to_string(port);
        rec = test::runGrabber(
            tmp, test::deriveGrabberIni("csi_channel_schedule.ini", keys, tmp.file("hop.ini")),
            seconds);
        tail = rec.log.substr(rec.log.size() > 6000 ? rec.log.size() - 6000 : 0);
    }
};

TEST(GrabberEmulator, ChannelScheduleFromTheScansOfBothBands)
{
    // `channel_schedule = scan`: both radios scan (eth6 the 5 GHz band, eth5 the 2.4 GHz one),
    // and the schedule is every channel heard, the capture's band first.
    HoppingRecording hop({"--retune-delay", "0.05", "--scan-time", "0.2"});
    ASSERT_TRUE(hop.emu.ready()) << hop.emu.log();
    MRPT_WIFI_REQUIRE_SSHD(hop.sshd);
    hop.record(
        {{"channel", "42/80"},
         {"channel_schedule", "scan"},
         {"scan_period", "30"},
         {"scan_wait", "0.3"},
         {"channel_dwell_s", "0.4"},
         {"rawlog_prefix", "scan"}},
        4.0);
    const auto& rec = hop.rec;
    const auto& tail = hop.tail;
    ASSERT_EQ(rec.exitCode, 0) << rec.log;
    EXPECT_NE(rec.log.find("channel schedule from the scan: 42/80 155/80 6/20"), std::string::npos)
        << tail;
    std::set<unsigned> heard;
    for (const auto& f : rec.frames) heard.insert(f->chanspec.centerChannel);
    EXPECT_EQ(heard, (std::set<unsigned>{6, 42, 155})) << tail;
    // The mean time without CSI per switch never exceeds the largest.
    std::smatch m;
    ASSERT_TRUE(
        std::regex_search(rec.log, m, std::regex("per switch ([0-9]+) ms mean, ([0-9]+) ms max")))
        << tail;
    EXPECT_LE(std::stoi(m[1]), std::stoi(m[2])) << tail;
}

TEST(GrabberEmulator, ChannelScheduleRecordsEveryChannelAndCountsTheSwitches)
{
    // share/scenarios/hopping.yaml: one AP on each of 42/80, 155/80 and 6/20. The grabber
    // visits the three channels in turn (channel_schedule), half a second each.
    const double retuneDelay_s = 0.05;
    HoppingRecording hop({"--retune-delay", std::to_string(retuneDelay_s)});
    ASSERT_TRUE(hop.emu.ready()) << hop.emu.log();
    MRPT_WIFI_REQUIRE_SSHD(hop.sshd);
    hop.record(
        {{"channel_schedule", "42/80 155/80 6/20"},
         {"channel_dwell_s", "0.5"},
         {"rawlog_prefix", "hop"}},
        5.0);
    const auto& rec = hop.rec;
    const auto& tail = hop.tail;
    ASSERT_EQ(rec.exitCode, 0) << rec.log;

    // Frames from every channel, each from the AP on that channel only.
    const std::map<unsigned, std::string> apOn = {
        {42, "02:00:00:00:06:01"}, {155, "02:00:00:00:06:02"}, {6, "02:00:00:00:06:03"}};
    std::map<unsigned, size_t> perChannel;
    size_t runs = 0;
    unsigned previous = 0;
    for (const auto& f : rec.frames)
    {
        const unsigned ch = f->chanspec.centerChannel;
        ASSERT_TRUE(apOn.count(ch)) << f->chanspec.asString();
        EXPECT_EQ(f->transmitter.asString(), apOn.at(ch));
        ++perChannel[ch];
        runs += ch != previous;
        previous = ch;
    }
    for (const auto& [ch, mac] : apOn)
        EXPECT_GT(perChannel[ch], 0u) << "channel " << ch << "\n" << tail;

    // The closing summary: the switches, what each cost, the frames per channel.
    const size_t closing = rec.log.rfind("channel schedule: ");
    ASSERT_NE(closing, std::string::npos) << tail;
    const std::string summary = rec.log.substr(closing);
    std::smatch m;
    ASSERT_TRUE(std::regex_search(
        summary, m,
        std::regex("channel schedule: ([0-9]+) switches, time without CSI per switch ([0-9]+) ms "
                   "mean, ([0-9]+) ms max.*frames lost to switching.*frames per channel: "
                   "6/20 ([0-9]+) \\(([0-9]+) visits\\) 42/80 ([0-9]+) \\(([0-9]+) visits\\) "
                   "155/80 ([0-9]+) \\(([0-9]+) visits\\)")))
        << tail;
    const int switches = std::stoi(m[1]);
    EXPECT_GE(switches, 3) << tail;  // at least one full round
    // A switch that retunes a radio costs at least its retune (the emulator's) plus the ssh
    // round trip (back to a band whose radio kept its channel, only the round trip).
    EXPECT_GE(std::stoi(m[3]), int(retuneDelay_s * 1000)) << tail;
    EXPECT_GT(std::stoi(m[2]), 0);
    EXPECT_GE(std::stoi(m[3]), std::stoi(m[2]));
    const int visits = std::stoi(m[5]) + std::stoi(m[7]) + std::stoi(m[9]);
    EXPECT_EQ(visits, switches + 1);  // the start-up configuration is the first visit
    // Only the channel being visited is heard (the 2.4 GHz radio stops when the schedule
    // moves to 5 GHz): the recording is one run of frames per visit, not an interleaving.
    EXPECT_LE(runs, size_t(visits)) << runs << " runs of frames on one channel";
    std::cout << rec.frames.size() << " frames: 6/20 " << perChannel[6] << ", 42/80 "
              << perChannel[42] << ", 155/80 " << perChannel[155] << "; " << m[0].str() << "\n";

    // The recording as a user takes it on: one calibration per channel from the emulator's
    // truth poses (on the receiver's clock), then bearings from every AP, each channel with
    // its own file. A few seconds of hopping are a short calibration drive, hence --force;
    // the accuracy of the files is CalibCli.EveryChannelOfAHoppingDriveCalibratedAndUsedAtOnce's.
    std::string rawlog;
    for (const auto& e : std::filesystem::directory_iterator(hop.tmp.path()))
        if (e.path().extension() == ".rawlog") rawlog = e.path().string();
    ASSERT_FALSE(rawlog.empty());
    const std::string truth = hop.emu.stateDir() + "/truth", calib = hop.tmp.file("calib");
    auto r = test::run(
        test::binDir() + "/wifi-calibrate -q " + rawlog + " --array " + MRPT_WIFI_SOURCE_DIR +
        "/share/arrays/rt-ac86u.yaml --transmitters " + truth + "/transmitters.yaml --poses " +
        truth + "/trajectory_tum.txt --force --out " + calib);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const char* cs : {"42/80", "155/80", "6/20"})
        EXPECT_TRUE(
            std::regex_search(r.output, std::regex(std::string("\n  ") + cs + " +: written")))
            << cs << "\n"
            << r.output;
    r = test::run(
        test::binDir() + "/csi-bearings -q -a aoa_only --require-calib -c " + calib + " " + rawlog +
        " " + hop.tmp.file("bearings.rawlog"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const auto& [ch, mac] : apOn)
    {
        const auto at = r.output.find(mac);
        ASSERT_NE(at, std::string::npos) << r.output;
        std::istringstream row(r.output.substr(at + mac.size()));
        uint64_t frames = 0, bearings = 0;
        row >> frames >> bearings;
        EXPECT_GT(bearings, frames / 2) << mac << "\n" << r.output;
    }
}
