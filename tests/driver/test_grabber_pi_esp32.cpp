// End to end with real parts, for the two live sources besides the router's UDP stream:
// Debian's rawlog-grabber loads libmrpt_wifi_sensor.so and records
//  - a Raspberry Pi's own chip (BCM43455c0): the emulator plays the Pi, its tools (nexutil,
//    makecsiparams, ip, iw) configured by the sensor locally or over a real sshd on 127.0.0.1,
//    and its CSI datagrams captured with libpcap on the loopback interface;
//  - an ESP32 (esp-csi CSI_DATA lines) on a serial port the emulator plays with a pty.
// What was recorded is compared with what the emulator says it sent (--record-sent).
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <mrpt_wifi/sensor/CsiDecoder.h>
#include <mrpt_wifi/sensor/CsiLiveSource.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <thread>

#include "EmulatorProcess.h"
#include "GrabberRun.h"
#include "SshdFixture.h"

using namespace mrpt_wifi;
using namespace std::chrono_literals;

namespace
{
std::string scenario(const std::string& name)
{
    return test::sourceDir() + "/share/scenarios/" + name + ".yaml";
}

/** True if libpcap captures on lo here: it opens (CAP_NET_RAW) and sees a datagram sent to
 *  127.0.0.1 (some sandboxes' kernels don't hand loopback traffic to packet sockets). */
bool liveCaptureOnLoopback(std::string& why)
{
    try
    {
        CsiLiveSourceOptions o;
        o.udpPort = test::freeLoopbackPort(SOCK_DGRAM);
        auto source = openLiveSource("interface:lo", o);
        const int sock = ::socket(AF_INET, SOCK_DGRAM, 0);
        sockaddr_in to{};
        to.sin_family = AF_INET;
        to.sin_port = htons(o.udpPort);
        to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        const char probe[] = "probe";
        ::sendto(sock, probe, sizeof(probe), 0, reinterpret_cast<const sockaddr*>(&to), sizeof(to));
        ::close(sock);
        for (int i = 0; i < 20 && source->stats().packets == 0; ++i)
            source->poll(
                [](const uint8_t*, size_t, mrpt::Clock::time_point, const std::string&) {}, {},
                50ms);
        if (source->stats().packets) return true;
        why =
            "the capture on lo saw no packet (this kernel doesn't deliver loopback traffic to "
            "packet sockets)";
    }
    catch (const std::exception& e)
    {
        why = e.what();
    }
    return false;
}

/** The recording holds the frames sent, in order, each with the same transmitter, sequence,
 *  channel, shape and every CSI value. rawlog-grabber writes half of its queue per period and
 *  drops the rest on exit, so the last one or two sent may be missing, nothing else. */
void expectSentFramesRecorded(
    const std::vector<CObservationWiFiCSI::Ptr>& live,
    const std::vector<CObservationWiFiCSI::Ptr>& sent)
{
    ASSERT_LE(live.size(), sent.size());
    ASSERT_GE(live.size() + 2, sent.size()) << "recorded " << live.size() << " of " << sent.size();
    for (size_t i = 0; i < live.size(); ++i)
    {
        const auto &a = *live[i], &b = *sent[i];
        ASSERT_EQ(a.transmitter, b.transmitter) << "frame " << i;
        ASSERT_EQ(a.sequenceNumber, b.sequenceNumber) << "frame " << i;
        ASSERT_EQ(a.chanspec, b.chanspec) << "frame " << i;
        ASSERT_EQ(a.nTx, b.nTx);
        ASSERT_EQ(a.nRx, b.nRx);
        ASSERT_EQ(a.source, b.source);
        ASSERT_EQ(a.csi.size(), b.csi.size());
        for (size_t k = 0; k < a.csi.size(); ++k)
            ASSERT_EQ(a.csi[k], b.csi[k]) << "frame " << i << " value " << k;
    }
}

/** `"key": value` somewhere in a JSON text (value as it is written, strings quoted). */
bool jsonHas(const std::string& json, const std::string& key, const std::string& value)
{
    return json.find("\"" + key + "\": " + value) != std::string::npos;
}
}  // namespace

TEST(GrabberPi, LocalControlConfiguresThePiAndItsCsiIsCapturedOnLoopback)
{
    std::string why;
    if (!liveCaptureOnLoopback(why))
        GTEST_SKIP() << "no libpcap live capture on lo here (needs CAP_NET_RAW): " << why;
    test::TempDir tmp;
    const uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);
    // 4 APs on 155/80 at 100 frames/s each; the Pi is off until the sensor sets it up, and
    // the emulator stops after 300 datagrams (< 1 s of CSI).
    test::EmulatorProcess emu(
        {"--device", "raspberry-pi", "--scenario", scenario("kidnapped"), "--fault-seed", "3",
         "--record-sent", tmp.file("sent.pcap"), "--max-datagrams", "300"},
        port, 30);
    ASSERT_TRUE(emu.ready()) << emu.log();

    const std::string wanted = "02:00:00:00:01:02";
    const auto ini = test::deriveGrabberIni(
        "csi_raspberry_pi.ini",
        {{"source", "interface:lo"},
         {"udp_port", std::to_string(port)},
         {"pi_control", "local"},
         {"pi_tool_dir", emu.toolsDir()},
         {"channel", "155/80"},
         {"packet_mac_filter", wanted},
         {"min_rssi_dBm", "-128"},
         {"status_period", "1"},
         {"rawlog_prefix", "pi"}},
        tmp.file("pi.ini"));
    const auto rec = test::runGrabber(tmp, ini, 4.0);
    ASSERT_EQ(rec.exitCode, 0) << rec.log;
    EXPECT_NE(rec.log.find("Raspberry Pi configured: CSI on 155/80"), std::string::npos) << rec.log;

    // The emulated Pi's state: what the sensor's commands did.
    const std::string summary = test::emulatorSummaryJson(emu.stateDir(), 10);
    ASSERT_FALSE(summary.empty()) << emu.log();
    EXPECT_TRUE(jsonHas(summary, "device", "\"raspberry-pi\"")) << summary;
    EXPECT_TRUE(jsonHas(summary, "monitor_interface", "\"mon0\"")) << summary;
    EXPECT_TRUE(jsonHas(summary, "monitor", "true")) << summary;
    EXPECT_TRUE(jsonHas(summary, "up", "true")) << summary;
    EXPECT_TRUE(jsonHas(summary, "chanspec", "\"155/80\"")) << summary;
    EXPECT_TRUE(jsonHas(summary, "core_mask", "1")) << summary;
    EXPECT_TRUE(jsonHas(summary, "nss_mask", "1")) << summary;
    EXPECT_TRUE(jsonHas(summary, "mac_filter", "[\"" + wanted + "\"]")) << summary;
    EXPECT_NE(emu.log().find("$ nexutil -Iwlan0 -s500 -b -l34 -v"), std::string::npos) << emu.log();

    // The hardware filter matches the first two bytes (all four APs pass); the sensor keeps
    // the one asked for. Everything the emulator sent of it was recorded, value for value.
    auto sent = test::decodeSentFrames(tmp.file("sent.pcap"), port);
    ASSERT_GT(sent.size(), 290u);
    sent.erase(
        std::remove_if(
            sent.begin(), sent.end(),
            [&](const auto& f) { return f->transmitter.asString() != wanted; }),
        sent.end());
    ASSERT_GT(sent.size(), 50u);
    for (const auto& f : rec.frames)
    {
        EXPECT_EQ(f->source, "bcm43455c0");
        EXPECT_EQ(f->nRx, 1);
        EXPECT_TRUE(f->isComplete());
        EXPECT_EQ(f->sensorLabel, "WIFI_CSI");
    }
    expectSentFramesRecorded(rec.frames, sent);
}

TEST(GrabberPi, RealBcm43455c0CaptureReplayedByTheConfiguredPiIsRecordedUnchanged)
{
    std::string why;
    if (!liveCaptureOnLoopback(why))
        GTEST_SKIP() << "no libpcap live capture on lo here (needs CAP_NET_RAW): " << why;
    test::TempDir tmp;
    const uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);
    const std::string sample = test::sourceDir() + "/tests/data/nexmon/bcm43455c0-80mhz.pcap";
    // The Pi replays CSIKit's real 43455c0 capture (8 frames on 42/80, 3.5 s, here at 4x),
    // round and round, but only once the sensor has tuned it there; 16 datagrams, then it stops.
    test::EmulatorProcess emu(
        {"--device", "raspberry-pi", "--replay", sample, "--speed", "4", "--loop", "--record-sent",
         tmp.file("sent.pcap"), "--max-datagrams", "16"},
        port, 30);
    ASSERT_TRUE(emu.ready()) << emu.log();
    const auto ini = test::deriveGrabberIni(
        "csi_raspberry_pi.ini",
        {{"source", "interface:lo"},
         {"udp_port", std::to_string(port)},
         {"pi_tool_dir", emu.toolsDir()},
         {"channel", "42/80"},
         {"min_rssi_dBm", "-128"},
         {"status_period", "1"},
         {"rawlog_prefix", "replay"}},
        tmp.file("replay.ini"));
    const auto rec = test::runGrabber(tmp, ini, 5.0);
    ASSERT_EQ(rec.exitCode, 0) << rec.log;
    const auto sent = test::decodeSentFrames(tmp.file("sent.pcap"), port);
    ASSERT_EQ(sent.size(), 16u) << emu.log();
    expectSentFramesRecorded(rec.frames, sent);
    // What went out are the capture's own frames, bytes unchanged: every one of the 8 appears.
    const auto original = test::decodeSentFrames(sample, 5500);
    ASSERT_EQ(original.size(), 8u);
    std::set<size_t> seen;
    for (const auto& f : sent)
        for (size_t k = 0; k < original.size(); ++k)
            if (original[k]->csi == f->csi && original[k]->rssi_dBm == f->rssi_dBm) seen.insert(k);
    EXPECT_EQ(seen.size(), 8u);
}

TEST(GrabberPi, SshControlOfThePiAndAChannelItCannotDoIsNamed)
{
    std::string why;
    if (!liveCaptureOnLoopback(why))
        GTEST_SKIP() << "no libpcap live capture on lo here (needs CAP_NET_RAW): " << why;
    test::TempDir tmp;
    const uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);
    test::EmulatorProcess emu(
        {"--device", "raspberry-pi", "--scenario", scenario("kidnapped"), "--fault-seed", "4",
         "--record-sent", tmp.file("sent.pcap"), "--max-datagrams", "400"},
        port, 30);
    ASSERT_TRUE(emu.ready()) << emu.log();
    test::SshdFixture sshd(emu.toolsDir());
    MRPT_WIFI_REQUIRE_SSHD(sshd);

    std::map<std::string, std::string> keys = {
        {"source", "interface:lo"},
        {"udp_port", std::to_string(port)},
        {"pi_control", "ssh"},
        {"login_host", "127.0.0.1"},
        {"login_port", std::to_string(sshd.port())},
        {"login_user", sshd.user()},
        {"login_identity_file", sshd.clientKey()},
        {"login_known_hosts", sshd.knownHosts()},
        {"channel", "155/80"},
        {"min_rssi_dBm", "-128"},
        {"status_period", "1"},
        {"rawlog_prefix", "pissh"}};
    const auto rec = test::runGrabber(
        tmp, test::deriveGrabberIni("csi_raspberry_pi.ini", keys, tmp.file("a.ini")), 7.0);
    ASSERT_EQ(rec.exitCode, 0) << rec.log;
    EXPECT_NE(rec.log.find("Raspberry Pi configured: CSI on 155/80"), std::string::npos) << rec.log;
    // No MAC filter: the four APs' CSI, one core each.
    std::set<std::string> macs;
    for (const auto& f : rec.frames)
    {
        macs.insert(f->transmitter.asString());
        ASSERT_EQ(f->chanspec.asString(), "155/80");
        ASSERT_EQ(f->source, "bcm43455c0");
    }
    // Not a fixed count (the ssh set-up takes what the machine's load makes it take): of what
    // the emulated Pi sent up to the last recorded frame, at most 1 % and the drops the sensor
    // reported are missing.
    ASSERT_FALSE(rec.frames.empty()) << rec.log << emu.log();
    emu.stop();  // closes the record of what was sent
    const auto cmp =
        test::compareWithSent(rec.frames, test::decodeSentFrames(tmp.file("sent.pcap"), port));
    EXPECT_EQ(cmp.neverSent, 0u);
    const size_t sentUpToLast = cmp.firstRecorded + cmp.sentInSpan;
    EXPECT_LE(
        cmp.firstRecorded + cmp.missing,
        test::lastReportedKernelDrops(rec.log) + sentUpToLast / 100)
        << rec.frames.size() << " recorded of " << sentUpToLast << " sent up to the last one";
    EXPECT_EQ(macs.size(), 4u);
    const std::string summary = test::emulatorSummaryJson(emu.stateDir(), 10);
    EXPECT_TRUE(jsonHas(summary, "monitor_interface", "\"mon0\"")) << summary;

    // The Pi can't capture 40 MHz on 2.4 GHz: the sensor refuses the file, naming the key
    // (rawlog-grabber reports it and ends; its exit code stays 0).
    keys["channel"] = "6/40";
    const auto bad = test::runGrabber(
        tmp, test::deriveGrabberIni("csi_raspberry_pi.ini", keys, tmp.file("b.ini")), 0.5);
    EXPECT_NE(bad.log.find("key 'channel'"), std::string::npos) << bad.log;
}

TEST(GrabberEsp32, EmulatedEsp32OnAPseudoTerminalIsRecordedLineForLine)
{
    test::TempDir tmp;
    const uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);  // unused by the ESP32
    const std::string tty = tmp.file("ttyESP32");
    // The IoT scenario's 3 devices on channel 6 (35 frames/s together): 60 lines, ~2 s.
    test::EmulatorProcess emu(
        {"--device", "esp32", "--preconfigured", "6/20", "--scenario", scenario("iot"),
         "--serial-link", tty, "--record-sent", tmp.file("sent.csv"), "--max-datagrams", "60"},
        port, 30);
    ASSERT_TRUE(emu.ready()) << emu.log();
    ASSERT_TRUE(std::filesystem::is_symlink(tty)) << emu.log();

    const auto ini = test::deriveGrabberIni(
        "csi_esp32.ini",
        {{"source", "serial:" + tty},
         {"serial_baud", "921600"},
         {"status_period", "1"},
         {"rawlog_prefix", "esp32"}},
        tmp.file("esp32.ini"));
    const auto rec = test::runGrabber(tmp, ini, 4.5);
    ASSERT_EQ(rec.exitCode, 0) << rec.log;
    const std::string summary = test::emulatorSummaryJson(emu.stateDir(), 10);
    EXPECT_TRUE(jsonHas(summary, "serial_lines_written", "60")) << summary;

    const auto sent = test::decodeSentFrames(tmp.file("sent.csv"), 0);
    ASSERT_EQ(sent.size(), 60u);
    std::set<std::string> macs;
    for (const auto& f : rec.frames)
    {
        macs.insert(f->transmitter.asString());
        EXPECT_EQ(f->source, "esp32");
        EXPECT_EQ(f->chanspec.asString(), "6/20");
        EXPECT_EQ(f->routerAddress, tty);
    }
    EXPECT_EQ(
        macs,
        (std::set<std::string>{"02:00:00:00:03:01", "02:00:00:00:03:02", "02:00:00:00:03:03"}));
    expectSentFramesRecorded(rec.frames, sent);
}
