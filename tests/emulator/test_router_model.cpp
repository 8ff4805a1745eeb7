// The router state machine and its tools, as WiROS's setup and a driver use them.
#include <gtest/gtest.h>
#include <mrpt_wifi/emulator/RouterModel.h>

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

/** WiROS's once-per-boot module load and one configuration. */
void setUp(RouterModel& r, double t, const std::string& ch = "155/80")
{
    for (const Argv& cmd :
         {Argv{"rmmod", "dhd"}, Argv{"insmod", "/jffs/csi/dhd.ko"},
          Argv{"brctl", "addif", "br0", "eth6"}, Argv{"wl", "-i", "eth6", "chanspec", ch},
          Argv{"wl", "-i", "eth6", "monitor", "1"},
          Argv{
              "nexutil", "-I", "eth6", "-s500", "-b", "-l34", "-v",
              params({"-e", "1", "-c", ch, "-C", "0xf", "-N", "0xf", "-d", "0x50"})}})
    {
        const auto res = r.execute(cmd, t);
        ASSERT_EQ(res.exitCode, 0) << cmd[0] << ": " << res.err;
    }
}
}  // namespace

TEST(EmulatorRouter, SilentAfterBootUntilTheModuleIsLoadedAndCsiConfigured)
{
    RouterModel r;
    EXPECT_EQ(r.module(), DriverModule::Stock);
    EXPECT_TRUE(r.activeCaptures(0).empty());
    // The stock firmware has no CSI ioctl.
    const auto res = r.execute(
        {"nexutil", "-I", "eth6", "-s500", "-b", "-l34", "-v",
         params({"-c", "155/80", "-C", "0xf", "-N", "0xf"})},
        0);
    EXPECT_NE(res.exitCode, 0);
    EXPECT_NE(res.err.find("stock firmware"), std::string::npos) << res.err;
    EXPECT_EQ(r.silenceReason(*r.findInterface("eth6"), 0), SilenceReason::StockFirmware);

    setUp(r, 1.0);
    EXPECT_EQ(r.module(), DriverModule::NexmonCsi);
    // Retuning to 155/80 right now, capturing once the retune delay has passed.
    EXPECT_TRUE(r.activeCaptures(1.0).empty());
    EXPECT_EQ(r.silenceReason(*r.findInterface("eth6"), 1.0), SilenceReason::Retuning);
    EXPECT_DOUBLE_EQ(r.nextTimedChange(1.0), 1.0 + r.timing().retuneDelay_s);
    const auto caps = r.activeCaptures(1.1);
    ASSERT_EQ(caps.size(), 1u);
    EXPECT_EQ(caps[0].interfaceName, "eth6");
    EXPECT_EQ(caps[0].chanspec.asString(), "155/80");
}

TEST(EmulatorRouter, NexutilAppliesExactlyTheRequestedParameters)
{
    RouterModel r;
    setUp(r, 0);
    const Argv request = {"-e",  "1",    "-c",  "155/80", "-C",
                          "0x5", "-N",   "0x3", "-m",     "02:aa:00:00:00:01,02:cc:00:00:00:03",
                          "-b",  "0x88", "-d",  "7"};
    ASSERT_EQ(
        r.execute({"nexutil", "-Ieth6", "-s", "500", "-b", "-l", "34", "-v", params(request)}, 1)
            .exitCode,
        0);
    const auto* itf = r.findInterface("eth6");
    ASSERT_TRUE(itf && itf->csi);
    EXPECT_EQ(*itf->csi, csiParamsFromArguments(request));
    EXPECT_EQ(itf->csi->coreMask, 0x5);
    EXPECT_EQ(itf->csi->nssMask, 0x3);
    EXPECT_EQ(itf->csi->delay_us, 7);
    ASSERT_EQ(itf->csi->macFilter.size(), 2u);
    EXPECT_EQ(itf->csi->macFilter[1].asString(), "02:cc:00:00:00:03");

    // -e 0 switches CSI off but keeps the module and channel.
    ASSERT_EQ(
        r.execute({"nexutil", "-I", "eth6", "-s500", "-b", "-l34", "-v", params({"-e", "0"})}, 2)
            .exitCode,
        0);
    EXPECT_EQ(r.silenceReason(*r.findInterface("eth6"), 3), SilenceReason::CsiDisabled);
}

TEST(EmulatorRouter, NexutilRejectsWrongLengthBadBase64AndWrongBand)
{
    RouterModel r;
    setUp(r, 0);
    const std::string good = params({"-c", "155/80", "-C", "1", "-N", "1"});
    const std::vector<Argv> bad = {
        {"nexutil", "-I", "eth6", "-s500", "-b", "-l33", "-v", good},  // -l vs value
        {"nexutil", "-I", "eth6", "-s500", "-b", "-l34", "-v", "not*base64"},
        {"nexutil", "-I", "eth6", "-s500", "-b", "-l3", "-v", "AAAA"},  // firmware: bad length
        {"nexutil", "-I", "eth6", "-s500", "-l34", "-v", good},         // no -b
        {"nexutil", "-I", "eth6", "-s500", "-b", "-v", good},           // no -l
        {"nexutil", "-I", "eth9", "-s500", "-b", "-l34", "-v", good},   // no such interface
        {"nexutil", "-I", "eth5", "-s500", "-b", "-l34", "-v", good},   // 5 GHz on 2.4 GHz
        {"nexutil", "-I", "eth6", "-s777", "-b", "-l34", "-v", good},   // unknown ioctl
        {"nexutil", "-I", "eth6", "-g500"},
        {"nexutil", "-Z"}};
    for (const auto& cmd : bad)
    {
        const auto res = r.execute(cmd, 1);
        EXPECT_NE(res.exitCode, 0) << cmd[1] << " " << (cmd.size() > 4 ? cmd[4] : "");
        EXPECT_FALSE(res.err.empty());
    }
    // Nothing of that changed the configuration.
    EXPECT_EQ(r.findInterface("eth6")->csi->coreMask, 0xf);
}

TEST(EmulatorRouter, WlChanspecMonitorAndDefaultInterface)
{
    RouterModel r;
    setUp(r, 0);
    auto res = r.execute({"wl", "-i", "eth6", "chanspec"}, 1);
    EXPECT_EQ(res.out, "149/80 (0xe09b)\n");  // Broadcom notation: control channel 149
    // The driver sets Broadcom's control-channel notation: 157/80 = centre 155, sideband 2.
    EXPECT_EQ(r.execute({"wl", "-i", "eth6", "chanspec", "157/80"}, 1).exitCode, 0);
    EXPECT_EQ(r.execute({"wl", "-i", "eth6", "chanspec"}, 1).out, "157/80 (0xe29b)\n");
    // Like the real wl, no -i means the first wireless adapter: eth5, 2.4 GHz.
    EXPECT_NE(r.execute({"wl", "chanspec", "155/80"}, 1).exitCode, 0);
    EXPECT_EQ(r.execute({"wl", "chanspec", "6/20"}, 1).exitCode, 0);
    EXPECT_EQ(r.execute({"wl", "-i", "eth6", "chanspec", "0xe02a"}, 1).exitCode, 0);
    EXPECT_EQ(r.findInterface("eth6")->chanspec.asString(), "42/80");
    EXPECT_NE(r.execute({"wl", "-i", "eth6", "chanspec", "155/60"}, 1).exitCode, 0);

    // Monitor mode is required for CSI.
    EXPECT_EQ(r.execute({"wl", "-i", "eth6", "monitor", "0"}, 2).exitCode, 0);
    EXPECT_EQ(r.execute({"wl", "-i", "eth6", "monitor"}, 2).out, "0\n");
    EXPECT_EQ(r.silenceReason(*r.findInterface("eth6"), 3), SilenceReason::MonitorOff);
    EXPECT_NE(r.execute({"wl", "-i", "eth6", "monitor", "maybe"}, 2).exitCode, 0);

    EXPECT_NE(r.execute({"wl", "-i", "eth6", "frobnicate"}, 2).exitCode, 0);
    EXPECT_NE(r.execute({"wl"}, 2).exitCode, 0);
    EXPECT_EQ(r.execute({"nosuchtool"}, 2).exitCode, 127);
}

TEST(EmulatorRouter, ModuleAndBridgeCommandsBehaveLikeBusybox)
{
    RouterModel r;
    EXPECT_NE(r.execute({"insmod", "/jffs/csi/dhd.ko"}, 0).exitCode, 0);  // stock one loaded
    EXPECT_EQ(r.execute({"rmmod", "dhd"}, 0).exitCode, 0);
    EXPECT_NE(r.execute({"rmmod", "dhd"}, 0).exitCode, 0);                   // nothing to unload
    EXPECT_NE(r.execute({"wl", "-i", "eth6", "chanspec"}, 0).exitCode, 0);   // no adapter
    EXPECT_NE(r.execute({"brctl", "addif", "br0", "eth6"}, 0).exitCode, 0);  // no interface
    EXPECT_NE(r.execute({"insmod", "/jffs/csi/other.ko"}, 0).exitCode, 0);
    EXPECT_EQ(r.execute({"insmod", "/jffs/csi/dhd.ko"}, 0).exitCode, 0);
    EXPECT_NE(r.execute({"brctl", "addif", "br1", "eth6"}, 0).exitCode, 0);
    EXPECT_EQ(r.execute({"brctl", "addif", "br0", "eth6"}, 0).exitCode, 0);
    EXPECT_NE(r.execute({"brctl", "addif", "br0", "eth6"}, 0).exitCode, 0);  // already
    EXPECT_NE(r.execute({"brctl", "show"}, 0).out.find("eth6"), std::string::npos);
    EXPECT_NE(r.execute({"lsmod"}, 0).out.find("dhd"), std::string::npos);

    // Without the bridge the datagrams don't reach the LAN.
    setUp(r, 1);
    EXPECT_EQ(r.activeCaptures(2).size(), 1u);
    EXPECT_EQ(r.execute({"brctl", "delif", "br0", "eth6"}, 2).exitCode, 0);
    EXPECT_EQ(r.silenceReason(*r.findInterface("eth6"), 3), SilenceReason::NotBridged);
}

TEST(EmulatorRouter, RebootForgetsEverythingAndIsUnreachableMeanwhile)
{
    RouterTiming timing;
    timing.rebootDuration_s = 0.5;
    RouterModel r(timing);
    setUp(r, 0);
    ASSERT_EQ(r.activeCaptures(1).size(), 1u);
    const uint64_t gen = r.generation();
    r.reboot(2.0);
    EXPECT_GT(r.generation(), gen);
    EXPECT_EQ(r.bootCount(), 1u);
    EXPECT_TRUE(r.activeCaptures(2.1).empty());
    EXPECT_EQ(r.execute({"wl", "-i", "eth6", "chanspec"}, 2.1).exitCode, kUnreachableExitCode);
    EXPECT_EQ(r.module(), DriverModule::Stock);
    EXPECT_FALSE(r.findInterface("eth6")->csi);
    EXPECT_TRUE(r.activeCaptures(3.0).empty());  // up again, but the setup must be redone
    setUp(r, 3.0);
    EXPECT_EQ(r.activeCaptures(3.1).size(), 1u);
}

TEST(EmulatorRouter, ScanReportsProviderResultsAfterTheScanTimeAndPausesCsi)
{
    RouterModel r;
    r.setScanProvider(
        [](WifiBand band)
        {
            ScanEntry a;
            a.ssid = "ap-a";
            a.bssid = MacAddress::fromString("02:aa:00:00:00:01");
            a.chanspec = Chanspec::fromString("155/80");
            a.rssi_dBm = -52;
            a.noise_dBm = -92;
            ScanEntry b = a;
            b.ssid = "ap-2g";
            b.chanspec = Chanspec::fromString("6/20");
            return band == WifiBand::Band5G ? std::vector<ScanEntry>{a} : std::vector<ScanEntry>{b};
        });
    setUp(r, 0);
    EXPECT_EQ(r.execute({"wl", "-i", "eth6", "scanresults"}, 1).out, "");  // no scan yet
    ASSERT_EQ(r.execute({"wl", "-i", "eth6", "scan"}, 1).exitCode, 0);
    EXPECT_EQ(r.silenceReason(*r.findInterface("eth6"), 1.5), SilenceReason::Scanning);
    const auto early = r.execute({"wl", "-i", "eth6", "scanresults"}, 1.5);
    EXPECT_NE(early.exitCode, 0);
    EXPECT_NE(early.err.find("Not Ready"), std::string::npos);
    const auto res = r.execute({"wl", "-i", "eth6", "scanresults"}, 1 + r.timing().scanDuration_s);
    ASSERT_EQ(res.exitCode, 0) << res.err;
    EXPECT_NE(res.out.find("SSID: \"ap-a\"\n"), std::string::npos) << res.out;
    EXPECT_NE(
        res.out.find("Mode: Managed\tRSSI: -52 dBm\tSNR: 40 dB\tnoise: -92 dBm"), std::string::npos)
        << res.out;
    EXPECT_NE(res.out.find("Channel: 149/80\n"), std::string::npos);
    EXPECT_NE(res.out.find("(0xe09b)"), std::string::npos);
    EXPECT_NE(res.out.find("BSSID: 02:AA:00:00:00:01\t"), std::string::npos);
    EXPECT_EQ(res.out.find("ap-2g"), std::string::npos);                    // other band
    EXPECT_EQ(r.activeCaptures(1 + r.timing().scanDuration_s).size(), 1u);  // CSI back
}

TEST(EmulatorRouter, BeaconInjectionIsCountedAsTransmitterMode)
{
    RouterModel r;
    setUp(r, 0);
    const std::string frame(100, 'x');
    const std::string b64 =
        base64Encode(reinterpret_cast<const uint8_t*>(frame.data()), frame.size());
    for (int i = 0; i < 3; ++i)
        ASSERT_EQ(
            r.execute({"nexutil", "-I", "eth6", "-s505", "-b", "-l", "100", "-v", b64}, 1).exitCode,
            0);
    EXPECT_EQ(r.findInterface("eth6")->framesInjected, 3u);
    EXPECT_EQ(r.findInterface("eth6")->lastInjectedLength, 100u);
    EXPECT_NE(
        r.execute({"nexutil", "-I", "eth6", "-s505", "-b", "-l", "4", "-v", "AAAAAA=="}, 1)
            .exitCode,
        0);
    EXPECT_NE(r.toJson(2).find("\"frames_injected\": 3"), std::string::npos);
    // The transmit rate the driver's transmitter mode sets first.
    EXPECT_EQ(r.execute({"wl", "-i", "eth6", "5g_rate", "-v", "0", "-s", "2"}, 3).exitCode, 0);
    EXPECT_EQ(r.execute({"wl", "-i", "eth6", "5g_rate"}, 3).out, "-v 0 -s 2\n");
    EXPECT_NE(r.execute({"wl", "-i", "eth6", "5g_rate", "-s", "9"}, 3).exitCode, 0);
    EXPECT_NE(r.execute({"wl", "-i", "eth6", "5g_rate", "-st", "1"}, 3).exitCode, 0);
}
