// NexmonPiControl (the Raspberry Pi's nexutil / makecsiparams / ip / iw) and the pi_* keys:
// the programs and arguments it runs, locally and through a shell, and what it refuses.
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt_wifi/sensor/CsiSensorSettings.h>
#include <mrpt_wifi/sensor/NexmonPiControl.h>

#include <fstream>

#include "SensorConfigError.h"
#include "TestSupport.h"

using namespace mrpt_wifi;

namespace
{
/** Records every argv; answers makecsiparams with `params`, `ip link show` per `monExists`. */
struct FakeRunner : CommandRunner
{
    std::vector<std::vector<std::string>> calls;
    std::string params = "m+ABEQAAAQACAAAAAQIAAAAAAAAAAAAAAAAAAAAAAAAAAA==\n";
    bool monExists = false;
    std::string run(const std::vector<std::string>& argv, double) override
    {
        calls.push_back(argv);
        if (argv[0] == "makecsiparams") return params;
        if (argv[0] == "ip" && argv[2] == "show" && !monExists)
            throw RouterError(RouterErrorKind::CommandFailed, "Device \"mon0\" does not exist.");
        return {};
    }
    std::string describe() const override { return "fake"; }
};

struct RecordingShell : RouterShell
{
    std::vector<std::string> commands;
    std::string run(const std::string& command, double) override
    {
        commands.push_back(command);
        return {};
    }
    std::string describe() const override { return "pi@127.0.0.1:22"; }
};

CsiExtractionSettings piSettings(const std::string& channel)
{
    CsiExtractionSettings s;
    s.chanspec = Chanspec::fromString(channel);
    s.coreMask = s.streamMask = 0x1;
    return s;
}

CsiSensorSettings load(const std::string& keys)
{
    mrpt::config::CConfigFileMemory cfg("[PI]\ndriver = CWiFiCSISensor\n" + keys);
    return loadCsiSensorSettings(cfg, "PI", "WIFI_CSI");
}
}  // namespace

TEST(PiControl, RunsNexmonCsiSetupStepsAsProgramsWithArguments)
{
    auto runner = std::make_shared<FakeRunner>();
    NexmonPiControl pi(runner, PiSetupOptions{});
    auto s = piSettings("155/80");
    s.macFilter = {MacAddress::fromString("02:00:00:00:01:02")};
    pi.configure(s);
    using V = std::vector<std::string>;
    ASSERT_EQ(runner->calls.size(), 6u);
    EXPECT_EQ(runner->calls[0], (V{"ip", "link", "set", "wlan0", "up"}));
    EXPECT_EQ(
        runner->calls[1], (V{"makecsiparams", "-c", s.chanspec.asBroadcomString(), "-C", "0x1",
                             "-N", "0x1", "-m", "02:00:00:00:01:02"}));
    // nexmon_csi's own spelling, the parameters makecsiparams printed (newline dropped).
    EXPECT_EQ(
        runner->calls[2], (V{"nexutil", "-Iwlan0", "-s500", "-b", "-l34",
                             "-vm+ABEQAAAQACAAAAAQIAAAAAAAAAAAAAAAAAAAAAAAAAAA=="}));
    EXPECT_EQ(runner->calls[3], (V{"ip", "link", "show", "mon0"}));
    EXPECT_EQ(
        runner->calls[4], (V{"iw", "dev", "wlan0", "interface", "add", "mon0", "type", "monitor"}));
    EXPECT_EQ(runner->calls[5], (V{"ip", "link", "set", "mon0", "up"}));
    // What the log shows: the same programs, the parameters as a placeholder.
    const auto shown = pi.configureCommands(s);
    ASSERT_EQ(shown.size(), 5u);
    EXPECT_EQ(shown[1], runner->calls[1]);
    EXPECT_EQ(shown[2].back(), "-v<params>");
    EXPECT_EQ(shown[3], runner->calls[4]);

    // Reconfiguring: mon0 exists now, so it is not added again.
    runner->calls.clear();
    runner->monExists = true;
    pi.configure(piSettings("36/20"));
    ASSERT_EQ(runner->calls.size(), 5u);
    EXPECT_EQ(runner->calls.back(), (V{"ip", "link", "set", "mon0", "up"}));

    // No monitor interface wanted: three programs.
    runner->calls.clear();
    PiSetupOptions noMon;
    noMon.monitorInterface.clear();
    NexmonPiControl(runner, noMon).configure(piSettings("6/20"));
    EXPECT_EQ(runner->calls.size(), 3u);
}

TEST(PiControl, MakecsiparamsGarbageIsAFirmwareErrorNotSentToNexutil)
{
    auto runner = std::make_shared<FakeRunner>();
    runner->params = "Usage: makecsiparams [-h] ...\n";
    NexmonPiControl pi(runner, PiSetupOptions{});
    try
    {
        pi.configure(piSettings("155/80"));
        FAIL() << "accepted makecsiparams' usage text as parameters";
    }
    catch (const RouterError& e)
    {
        EXPECT_EQ(e.kind(), RouterErrorKind::WrongFirmware);
        EXPECT_NE(std::string(e.what()).find("makecsiparams printed"), std::string::npos);
    }
    for (const auto& c : runner->calls) EXPECT_NE(c[0], "nexutil");
}

TEST(PiControl, OverSshEveryArgumentIsOneQuotedWord)
{
    auto shell = std::make_shared<RecordingShell>();
    PiSetupOptions o;
    o.toolDir = "/opt/nexmon/bin";
    NexmonPiControl pi(std::make_shared<ShellCommandRunner>(shell, o.toolDir), o);
    auto s = piSettings("36/80");
    EXPECT_THROW(pi.configure(s), RouterError);  // the recording shell prints no parameters
    ASSERT_EQ(shell->commands.size(), 2u);
    EXPECT_EQ(shell->commands[0], "/opt/nexmon/bin/ip link set wlan0 up");
    EXPECT_EQ(shell->commands[1].rfind("/opt/nexmon/bin/makecsiparams -c ", 0), 0u);

    ShellCommandRunner runner(shell);
    runner.run({"echo", "a b", "it's", "$(reboot)"}, 1);
    EXPECT_EQ(shell->commands.back(), "echo 'a b' 'it'\\''s' '$(reboot)'");
}

TEST(PiControl, LocalRunnerRunsProgramsWithoutAShellAndNamesWhatFailed)
{
    test::TempDir dir;
    const std::string tool = dir.file("makecsiparams");
    std::ofstream(tool) << "#!/bin/sh\nprintf '%s\\n' \"$#:$1\"\n";
    std::filesystem::permissions(tool, std::filesystem::perms::owner_all);
    LocalCommandRunner runner(dir.path());
    // One argument with spaces and a substitution stays one argument: no shell in between.
    EXPECT_EQ(runner.run({"makecsiparams", "a b $(id)"}, 5), "1:a b $(id)\n");
    try
    {
        runner.run({"nexutil", "-Iwlan0"}, 5);
        FAIL();
    }
    catch (const RouterError& e)
    {
        EXPECT_EQ(e.kind(), RouterErrorKind::CommandMissing);
        EXPECT_NE(std::string(e.what()).find("nexutil"), std::string::npos) << e.what();
    }
}

TEST(PiControl, IniKeysAndBadValuesNameTheKey)
{
    const auto s = load(
        "source = interface:lo\npi_control = local\npi_interface = wlan1\npi_monitor_interface "
        "=\npi_tool_dir = /opt/nexmon/bin\nchannel = 36/80\npacket_mac_filter = "
        "02:00:00:00:01:02\n");
    EXPECT_EQ(s.piControl, CsiSensorSettings::PiControl::Local);
    EXPECT_EQ(s.pi.interface, "wlan1");
    EXPECT_TRUE(s.pi.monitorInterface.empty());
    EXPECT_EQ(s.pi.toolDir, "/opt/nexmon/bin");
    EXPECT_EQ(s.extraction.coreMask, 0x1);  // the Pi's default: one core, one stream
    EXPECT_EQ(s.extraction.streamMask, 0x1);
    EXPECT_EQ(s.extraction.chanspec.bandwidthMHz, 80u);
    EXPECT_EQ(load("pi_control = ssh\n").piControl, CsiSensorSettings::PiControl::Ssh);
    EXPECT_EQ(load("").piControl, CsiSensorSettings::PiControl::Off);

    const auto expectKey = [](const std::string& keys, const std::string& key)
    {
        const std::string what = test::sensorConfigError("[CSI]\ndriver = CWiFiCSISensor\n" + keys);
        EXPECT_NE(what.find("'" + key + "'"), std::string::npos) << keys << " → " << what;
    };
    expectKey("pi_control = yes\n", "pi_control");
    expectKey("pi_control = local\npi_interface = wlan0;reboot\n", "pi_interface");
    expectKey("pi_control = local\npi_interface = a-very-long-interface-name\n", "pi_interface");
    expectKey("pi_control = ssh\npi_monitor_interface = mon 0\n", "pi_monitor_interface");
    expectKey("pi_control = local\npi_tool_dir = bin\n", "pi_tool_dir");
    // Channels the bandwidth doesn't have, or the Pi's chip can't capture.
    expectKey("pi_control = local\nchannel = 165/80\n", "channel");
    expectKey("pi_control = local\nchannel = 50/80\n", "channel");
    expectKey("pi_control = local\nchannel = 38/20x\n", "channel");
    expectKey("pi_control = local\nchannel = 6/40\n", "channel");
    expectKey("pi_control = local\nchannel = 50/160\n", "channel");
    expectKey("pi_control = local\ncore_mask = 0xf\n", "core_mask");
    expectKey("pi_control = local\nstream_mask = 0x3\n", "stream_mask");
    expectKey("pi_interface = wlan0\n", "pi_interface");  // without pi_control
    const std::string both = test::sensorConfigError(
        "[CSI]\ndriver = CWiFiCSISensor\nrouter_control = true\npi_control = local\n");
    EXPECT_NE(both.find("pi_control"), std::string::npos) << both;
}
