// The emulated Raspberry Pi (RouterKind::RaspberryPi: nexutil, makecsiparams, ip, iw on one
// dual-band wlan0) and the encoders the emulator's Pi and ESP32 use, checked against the
// decoders the sensor uses.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <mrpt_wifi/emulator/Emulator.h>
#include <mrpt_wifi/emulator/RouterModel.h>
#include <mrpt_wifi/emulator/SerialPty.h>
#include <mrpt_wifi/sensor/Esp32CsiFormat.h>
#include <mrpt_wifi/sensor/NexmonFormat.h>
#include <unistd.h>

#include <filesystem>
#include <random>

#include "TestSupport.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::emulator;

namespace
{
std::string params(const Argv& args)
{
    std::string s = makeCsiParams(args).out;
    while (!s.empty() && s.back() == '\n') s.pop_back();
    return s;
}

ToolResult run(RouterModel& r, const Argv& cmd, double t = 0)
{
    return r.execute(cmd, t);
}

CObservationWiFiCSI randomFrame(const std::string& channel, unsigned seed)
{
    CObservationWiFiCSI obs;
    obs.chanspec = Chanspec::fromString(channel);
    obs.resize(1, 1, obs.nfft());
    obs.setPresent(0, 0);
    obs.transmitter = MacAddress::fromString("02:00:00:00:03:02");
    obs.sequenceNumber = 1234;
    obs.rssi_dBm = -47;
    std::mt19937 rng(seed);
    std::normal_distribution<float> n(0, 300);
    for (auto& v : obs.csi) v = {n(rng), n(rng)};
    return obs;
}
}  // namespace

TEST(EmulatorPi, NexmonCsiReadmeStepsMakeTheChipReport)
{
    RouterModel pi({}, RouterKind::RaspberryPi);
    EXPECT_EQ(pi.module(), DriverModule::NexmonCsi);  // the patched firmware is installed
    ASSERT_EQ(pi.interfaces().size(), 1u);
    EXPECT_EQ(pi.interfaces()[0].name, "wlan0");
    EXPECT_TRUE(pi.activeCaptures(0).empty());
    // The router's tools are not on a Pi.
    EXPECT_EQ(run(pi, {"wl", "ver"}).exitCode, 127);
    EXPECT_EQ(run(pi, {"insmod", "dhd.ko"}).exitCode, 127);

    ASSERT_EQ(run(pi, {"ip", "link", "set", "wlan0", "up"}).exitCode, 0);
    const auto p = params({"-c", "36/80", "-C", "1", "-N", "1", "-m", "02:00:00:00:01:02"});
    ASSERT_EQ(run(pi, {"nexutil", "-Iwlan0", "-s500", "-b", "-l34", "-v" + p}).exitCode, 0);
    // CSI configured and the radio tuned, but no monitor interface yet.
    EXPECT_TRUE(pi.activeCaptures(1).empty());
    EXPECT_EQ(pi.silenceReason(pi.interfaces()[0], 1), SilenceReason::MonitorOff);
    EXPECT_NE(run(pi, {"ip", "link", "show", "mon0"}).exitCode, 0);
    ASSERT_EQ(
        run(pi, {"iw", "dev", "wlan0", "interface", "add", "mon0", "type", "monitor"}).exitCode, 0);
    EXPECT_EQ(run(pi, {"ip", "link", "show", "mon0"}).exitCode, 0);
    EXPECT_TRUE(pi.activeCaptures(1).empty());  // created down
    ASSERT_EQ(run(pi, {"ip", "link", "set", "mon0", "up"}).exitCode, 0);
    const auto caps = pi.activeCaptures(1);
    ASSERT_EQ(caps.size(), 1u);
    EXPECT_EQ(caps[0].chanspec.asString(), "42/80");
    EXPECT_EQ(caps[0].csi.macFilter.size(), 1u);
    // Down again: silent, with the reason.
    ASSERT_EQ(run(pi, {"ifconfig", "wlan0", "down"}).exitCode, 0);
    EXPECT_EQ(pi.silenceReason(pi.interfaces()[0], 1), SilenceReason::InterfaceDown);
    EXPECT_NE(pi.toJson(1).find("\"device\": \"raspberry-pi\""), std::string::npos) << pi.toJson(1);
}

TEST(EmulatorPi, OneWlan0ForBothBandsButOnlyTheBandwidthsTheChipHas)
{
    RouterModel pi({}, RouterKind::RaspberryPi);
    const auto set = [&](const std::string& ch)
    {
        return run(pi, {"nexutil", "-Iwlan0", "-s500", "-b", "-l34",
                        "-v" + params({"-c", ch, "-C", "1", "-N", "1"})})
            .exitCode;
    };
    EXPECT_EQ(set("6"), 0);
    EXPECT_EQ(pi.interfaces()[0].band, WifiBand::Band2G4);
    EXPECT_EQ(set("157/80"), 0);
    EXPECT_EQ(pi.interfaces()[0].band, WifiBand::Band5G);
    EXPECT_NE(set("6/40"), 0);  // 2.4 GHz: 20 MHz only on the 43455c0
    EXPECT_EQ(pi.interfaces()[0].chanspec.asString(), "155/80");
    // Unknown interfaces and malformed commands fail like the real tools.
    EXPECT_NE(run(pi, {"ip", "link", "set", "wlan9", "up"}).exitCode, 0);
    EXPECT_NE(
        run(pi, {"iw", "dev", "wlan9", "interface", "add", "mon0", "type", "monitor"}).exitCode, 0);
    EXPECT_NE(run(pi, {"ip", "route"}).exitCode, 0);
}

TEST(EmulatorPi, Int16DatagramsOfThe43455c0DecodeToTheRoundedValues)
{
    auto obs = randomFrame("155/80", 1);
    obs.headerVariant = NexmonHeaderVariant::Nexmon;
    const auto datagrams = nexmon::encodeFrame(obs, nexmon::Chip::BCM43455c0);
    ASSERT_EQ(datagrams.size(), 1u);
    nexmon::DatagramHeader h;
    nexmon::RejectReason why;
    ASSERT_TRUE(nexmon::parseHeader(
        datagrams[0].data(), datagrams[0].size(), nexmon::FormatHint::Auto, h, why));
    EXPECT_EQ(h.chip, nexmon::Chip::BCM43455c0);
    EXPECT_EQ(h.chipId, nexmon::kChip43455c0);
    EXPECT_EQ(h.core, 0);
    EXPECT_EQ(h.transmitter, obs.transmitter);
    std::vector<std::complex<float>> back(h.nfft());
    nexmon::decodeWords(h.chip, datagrams[0].data() + nexmon::csiOffset(), h.nfft(), back.data());
    for (unsigned i = 0; i < h.nfft(); ++i)
    {
        EXPECT_EQ(back[i].real(), std::round(obs.csi[i].real())) << i;
        EXPECT_EQ(back[i].imag(), std::round(obs.csi[i].imag())) << i;
    }
    EXPECT_THROW(nexmon::encodeFrame(obs, nexmon::Chip::BCM4358), std::invalid_argument);
}

TEST(EmulatorEsp32, CsiLinesParseBackToTheScaledLltf)
{
    const auto obs = randomFrame("6/20", 2);
    const std::string line = esp32CsiLine(obs, 7, 123456, 60);
    ASSERT_EQ(line.back(), '\n');
    esp32::Esp32Line l;
    std::string why;
    ASSERT_TRUE(esp32::parseLine(line.substr(0, line.size() - 1), l, why)) << why << "\n" << line;
    EXPECT_EQ(l.seq, 7u);
    EXPECT_EQ(l.mac, obs.transmitter);
    EXPECT_EQ(l.rssi, -47);
    EXPECT_EQ(l.channel, 6u);
    EXPECT_EQ(l.localTimestamp_us, 123456u);
    ASSERT_EQ(l.values.size(), 128u);
    CObservationWiFiCSI back;
    ASSERT_TRUE(esp32::toObservation(l, back, why)) << why;
    EXPECT_EQ(back.chanspec.asString(), "6/20");
    // The largest component is ±60; every L-LTF subcarrier is the frame's, scaled and rounded.
    float maxAbs = 0;
    for (const auto& v : obs.csi)
        maxAbs = std::max({maxAbs, std::abs(v.real()), std::abs(v.imag())});
    const float scale = 60.0f / maxAbs;
    int largest = 0;
    for (int8_t v : l.values) largest = std::max(largest, std::abs(int(v)));
    EXPECT_EQ(largest, 60);
    for (int k : esp32::lltfSubcarriers())
    {
        const auto want = obs.csi[unsigned(k + 32)] * scale;
        const auto got = back.csi[unsigned(k + 32)];
        EXPECT_NEAR(got.real(), want.real(), 0.5f + 1e-4f) << k;
        EXPECT_NEAR(got.imag(), want.imag(), 0.5f + 1e-4f) << k;
    }
    EXPECT_THROW(esp32CsiLine(randomFrame("155/80", 3), 1, 0), std::invalid_argument);
}

TEST(EmulatorEsp32, PseudoTerminalDeliversQueuedLinesToAReaderWhoComesLater)
{
    char dirTemplate[] = "/tmp/mrpt_wifi_pty_XXXXXX";
    ASSERT_TRUE(::mkdtemp(dirTemplate));
    const std::string link = std::string(dirTemplate) + "/ttyESP32";
    std::string got;
    {
        PtySerialPort port(link);
        EXPECT_EQ(port.devicePath(), link);
        std::vector<std::string> written;
        for (int i = 0; i < 5; ++i) ASSERT_TRUE(port.submit("line " + std::to_string(i) + "\n"));
        port.flush([&](const std::string& l) { written.push_back(l); });
        EXPECT_EQ(written.size(), 5u);
        EXPECT_FALSE(port.pending());
        // Nobody has read them yet (the terminal moves them to the reader's side shortly).
        for (int i = 0; i < 100 && port.unreadBytes() < 35; ++i) ::usleep(2000);
        EXPECT_EQ(port.unreadBytes(), 35u);
        const int fd = ::open(link.c_str(), O_RDONLY | O_NOCTTY | O_NONBLOCK);
        ASSERT_GE(fd, 0);
        char buf[256];
        const ssize_t n = ::read(fd, buf, sizeof(buf));
        ASSERT_GT(n, 0);
        got.assign(buf, size_t(n));
        EXPECT_EQ(port.unreadBytes(), 0u);
        ::close(fd);
    }
    EXPECT_EQ(got, "line 0\nline 1\nline 2\nline 3\nline 4\n");
    EXPECT_FALSE(std::filesystem::exists(link));  // the link goes with the port
    ::rmdir(dirTemplate);
}

TEST(EmulatorDevices, ImpossibleDeviceSettingsAreRefusedBeforeAnythingIsSent)
{
    const auto options = [](EmulatedDevice d)
    {
        EmulatorOptions o;
        o.device = d;
        o.scenarioFile = test::sourceDir() + "/share/scenarios/iot.yaml";
        o.port = 9;  // nothing is sent: the constructor refuses first
        return o;
    };
    const auto refused = [](const EmulatorOptions& o, const std::string& what)
    {
        try
        {
            Emulator e(o);
            ADD_FAILURE() << "accepted; expected: " << what;
        }
        catch (const std::exception& e)
        {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    };
    refused(options(EmulatedDevice::Esp32), "--preconfigured");
    auto o = options(EmulatedDevice::Esp32);
    o.preconfigured = Chanspec::fromString("155/80");
    refused(o, "20 MHz");
    o = options(EmulatedDevice::RaspberryPi);
    o.format = NexmonHeaderVariant::UbiLocate;
    refused(o, "Raspberry Pi");
    o = options(EmulatedDevice::RtAc86u);
    o.serialLink = "/tmp/x";
    refused(o, "esp32");
    EXPECT_THROW(emulatedDeviceFromString("pi"), std::invalid_argument);
    EXPECT_EQ(emulatedDeviceFromString("raspberry-pi"), EmulatedDevice::RaspberryPi);
}
